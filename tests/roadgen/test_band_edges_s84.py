"""A band's lower end keeps the harmonic that lies a relative 1/N below it (`band_edges`' own
example): on a 150 m road at 6 mm (N = 25,001 points, period 150.006 m), n_min = 0.1 cycles/m
keeps the 15th harmonic at 0.099996 cycles/m, and nothing below it. (Session 84's mutation
testing: a lower edge without the 1/N allowance dropped that harmonic and passed every test.)"""

import numpy as np

import roadgen


def test_the_lowest_harmonic_a_relative_one_over_n_below_n_min_is_kept():
    profile = roadgen.iso8608_profile(150.0, 300.0, 0.006, seed=1, band=(0.1, 10.0), lead_in_m=0.0)
    spectrum = np.abs(np.fft.rfft(profile.z))
    assert profile.z.size == 25_001 and 15 / (25_001 * 0.006) < 0.1
    scale = spectrum[15:40].mean()
    assert spectrum[15] > 0.1 * scale  # kept (Rayleigh-free amplitudes: ~1.7 times the mean)
    assert np.all(spectrum[1:15] < 1e-12 * scale)  # below the band: nothing
