"""Independent reference: the linear (bilateral-contact) models solved as state-space systems.

Written from the equations of motion, not from the Exudyn models, to validate them. Generalised
coordinates: HalfCar q = [y1, y2, y3, phi3] (front axle, rear axle, body heave, body pitch);
Jackal q = [y, phi] (heave, pitch). All vertical motions are deviations from static equilibrium;
``phi`` is positive when the front rises. The model is ``M q'' + C q' + K q = Kt u + Ct u'``
with the road heights ``u = [u1, u2]`` under the front and rear tyre.

The paper's eq. 1 prints the suspension terms of the axle equations (and the rear-suspension
moment in the pitch equation) with a flipped sign, which would make the suspension push the wheel
away from equilibrium; the physically consistent signs are used here (symmetric, positive-definite
stiffness matrix), and they agree with eq. 1 everywhere else.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from roadgen.errors import distinct_texts
from vehicle import checks
from vehicle.errors import SolverStepWarning, VehicleError, user_stacklevel
from vehicle.kinematics import check_speed
from vehicle.models import HalfCar, Jackal, Model, check_model
from vehicle.road_input import RoadInput

if TYPE_CHECKING:
    from scipy import signal

BYTES_PER_POINT = 256
"""Memory per point of ``linear_response``'s fine time grid (n_samples * oversample points):
the time and position grids, the road inputs (4 per point) and lsim's states and outputs
(measured: ~150 for the Jackal, ~215 for the HalfCar)."""


MAX_OMEGA_H = 0.25
"""Largest omega h (the stiffest undamped mode's angular frequency times the solver's fixed
step) that `warn_if_step_too_coarse` lets pass. Measured on the Jackal without lift-off against
``linear_response`` (4 m, GD 400, 1 m/s): the acceleration's variance is within 1.5% up to
omega h = 0.25 (tyres 5x the default stiffness), 13% low at 0.35 and half at 0.78 (50x); the
default models sit at 0.11-0.12 at 120 Hz and 5 substeps."""


def highest_mode_rad_s(model: Model) -> float:
    """The angular frequency of the model's stiffest undamped mode (sqrt of the largest
    eigenvalue of M^-1 K, linear bilateral contact), rad/s."""
    lm = linear_model(model)
    eig = np.linalg.eigvals(np.linalg.solve(lm.mass, lm.stiffness)).real
    return float(np.sqrt(max(float(eig.max()), 0.0)))


def warn_if_step_too_coarse(model: Model, rate_hz: float, substeps: int) -> None:
    """Warn (`SolverStepWarning`) when the fixed step 1 / (rate_hz substeps) s resolves the
    model's stiffest mode too coarsely (omega h > MAX_OMEGA_H), naming the substeps that would;
    the warning names the user's call (`user_stacklevel`: past vehicle's frames and those of a
    package marked as its wrapper, control's closed loop)."""
    omega = highest_mode_rad_s(model)
    omega_h = omega / (rate_hz * substeps)
    if omega_h > MAX_OMEGA_H:
        step = MAX_OMEGA_H * rate_hz
        need = omega / step if step > 0 else math.inf  # inf for an absurdly low rate_hz
        fix = f"substeps >= {math.ceil(need)}" if need < 1e15 else "a higher rate_hz"
        shown = f"{omega_h:.2f}"  # exact where two decimals would read as the limit
        shown = repr(omega_h) if shown == f"{MAX_OMEGA_H:.2f}" else shown
        warnings.warn(
            f"the model's stiffest mode ({omega / (2 * np.pi):.4g} Hz) is too fast for the solver "
            f"step 1/({rate_hz:g} x {substeps}) s (omega h = {shown} > {MAX_OMEGA_H}): its "
            f"accelerations would be biased (half the variance at omega h = 0.8); use {fix}",
            SolverStepWarning,
            stacklevel=user_stacklevel(),
        )


@dataclass(frozen=True)
class LinearModel:
    """Matrices of ``M q'' + C q' + K q = Kt u + Ct u'`` and the front/rear axle selectors.

    mass, damping, stiffness: (d, d). tyre_stiffness, tyre_damping: (d, 2), the road inputs'
    force gains. front, rear: (d,) rows giving the axle displacement from q.
    """

    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    tyre_stiffness: np.ndarray
    tyre_damping: np.ndarray
    front: np.ndarray
    rear: np.ndarray


def linear_model(model: Model) -> LinearModel:
    """The linearised equations of motion of ``model`` (bilateral tyre contact)."""
    check_model(model)
    b1, b2 = model.b1_m, model.b2_m
    if isinstance(model, Jackal):
        kt, ct = model.axle_stiffness_n_per_m, model.axle_damping_ns_per_m
        front, rear = np.array([1.0, b1]), np.array([1.0, -b2])
        arms = np.stack([front, rear], axis=1)  # (2, 2): generalised force of each tyre
        lm = LinearModel(
            mass=np.diag([model.mass_kg, model.pitch_inertia_kgm2]),
            damping=ct * arms @ arms.T,
            stiffness=kt * arms @ arms.T,
            tyre_stiffness=kt * arms,
            tyre_damping=ct * arms,
            front=front,
            rear=rear,
        )
        return _check_finite(model, lm)
    assert isinstance(model, HalfCar)
    k1, k2 = model.suspension_stiffness_front_n_per_m, model.suspension_stiffness_rear_n_per_m
    c1, c2 = model.suspension_damping_front_ns_per_m, model.suspension_damping_rear_ns_per_m
    kt, ct = model.tyre_stiffness_n_per_m, model.tyre_damping_ns_per_m
    # suspension deflections: d1 = y3 + b1 phi - y1, d2 = y3 - b2 phi - y2
    d1 = np.array([-1.0, 0.0, 1.0, b1])
    d2 = np.array([0.0, -1.0, 1.0, -b2])
    tyre1 = np.array([1.0, 0.0, 0.0, 0.0])
    tyre2 = np.array([0.0, 1.0, 0.0, 0.0])
    tyres = np.stack([tyre1, tyre2], axis=1)
    stiffness = k1 * np.outer(d1, d1) + k2 * np.outer(d2, d2) + kt * tyres @ tyres.T
    damping = c1 * np.outer(d1, d1) + c2 * np.outer(d2, d2) + ct * tyres @ tyres.T
    lm = LinearModel(
        mass=np.diag(
            [
                model.unsprung_mass_front_kg,
                model.unsprung_mass_rear_kg,
                model.sprung_mass_kg,
                model.pitch_inertia_kgm2,
            ]
        ),
        damping=damping,
        stiffness=stiffness,
        tyre_stiffness=kt * tyres,
        tyre_damping=ct * tyres,
        front=tyre1,
        rear=tyre2,
    )
    return _check_finite(model, lm)


def _check_finite(model: Model, lm: LinearModel) -> LinearModel:
    """``lm``, or VehicleError naming the mass or inertia field over which a stiffness or
    damping (M^-1 K, M^-1 C and the road gains) overflows: fields far too large or too small."""
    rows = (
        ("mass_kg", "pitch_inertia_kgm2")
        if isinstance(model, Jackal)
        else ("unsprung_mass_front_kg", "unsprung_mass_rear_kg", "sprung_mass_kg",
              "pitch_inertia_kgm2")
    )  # fmt: skip
    with np.errstate(over="ignore", invalid="ignore"):
        inv_mass = 1.0 / np.diag(lm.mass)[:, None]  # both models' mass matrices are diagonal
        gains = np.hstack([lm.stiffness, lm.damping, lm.tyre_stiffness, lm.tyre_damping]) * inv_mass
    bad = ~np.all(np.isfinite(gains), axis=1)
    if np.any(bad):
        field = rows[int(np.argmax(bad))]
        raise VehicleError(
            f"{model.name}: a stiffness or damping over {model.name}.{field}="
            f"{getattr(model, field)!r} overflows its equations of motion: the fields are out "
            "of range (far too large or too small)"
        )
    return lm


def state_space(lm: LinearModel) -> signal.StateSpace:
    """State x = [q, q'], input [u1, u2, u1', u2'], output [a_front, a_rear, q (d)]."""
    from scipy import signal  # here, not at import (tests/test_import_cost.py)

    d = lm.mass.shape[0]
    acc_x = np.linalg.solve(lm.mass, np.hstack([-lm.stiffness, -lm.damping]))  # (d, 2d)
    acc_u = np.linalg.solve(lm.mass, np.hstack([lm.tyre_stiffness, lm.tyre_damping]))  # (d, 4)
    a = np.block([[np.zeros((d, d)), np.eye(d)], [acc_x]])
    b = np.vstack([np.zeros((d, 4)), acc_u])
    axles = np.stack([lm.front, lm.rear])
    c = np.vstack([axles @ acc_x, np.hstack([np.eye(d), np.zeros((d, d))])])
    dd = np.vstack([axles @ acc_u, np.zeros((d, 4))])
    return signal.StateSpace(a, b, c, dd)


@dataclass(frozen=True)
class LinearTrace:
    """Linear reference at t = k / rate_hz, k = 1..n: accel_front, accel_rear (m/s^2), q (n, d)."""

    t: np.ndarray
    accel_front: np.ndarray
    accel_rear: np.ndarray
    q: np.ndarray


def linear_response(
    model: Model,
    road,
    speed: float,
    n_samples: int,
    rate_hz: float = 120.0,
    start_m: float | None = None,
    oversample: int = 20,
    envelope: bool = True,
) -> LinearTrace:
    """Response of the linear model at constant ``speed`` (m/s), from rest on the road.

    The front axle starts at ``start_m`` (default: wheelbase; in [0, road length), the rear axle
    reading a flat extension at the road's first height while behind its start), as in
    ``simulate``, and its last sample must lie on the road. The road input is evaluated on a grid
    ``oversample`` times finer than the samples and interpolated linearly by ``lsim``;
    ``envelope`` as in ``simulate``.

    Raises VehicleError for a speed outside (0, model.max_speed_mps], n_samples or oversample
    not an integer >= 1, a rate_hz not finite and > 0, a start_m not finite or off the road, a
    road no longer than the wheelbase, n_samples that take the front axle past the road's end,
    an envelope not a bool, a grid that would need more than
    ``vehicle.checks.MAX_MEMORY_BYTES``, or a model whose fields are so far out of range (a
    mass of 1e-300 kg) that its response overflows.
    """
    check_model(model)
    speed = checks.real("speed", speed)
    check_speed("speed", speed, model.max_speed_mps)
    n_samples = checks.integer("n_samples", n_samples, 1)
    rate_hz = checks.positive("rate_hz", rate_hz, unit="Hz")
    oversample = checks.integer("oversample", oversample, 1)
    checks.memory(
        BYTES_PER_POINT * (n_samples * oversample + 1.0),
        f"a linear response of n_samples={n_samples} x oversample={oversample} points",
    )
    wb = model.wheelbase_m
    s0 = wb if start_m is None else checks.real("start_m", start_m)
    if not np.isfinite(s0):
        raise VehicleError(f"start_m={start_m!r} must be finite")
    envelope = checks.flag("envelope", envelope)
    road_in = RoadInput(road, model.wheel_radius_m if envelope else None)
    _check_drive(model, road_in, s0, speed, n_samples, rate_hz)
    lm = linear_model(model)
    t = np.arange(n_samples * oversample + 1) / (rate_hz * oversample)
    s = s0 + speed * t
    u = np.stack(
        [
            road_in.heights(s),
            road_in.heights(s - wb),
            speed * road_in.slopes(s),
            speed * road_in.slopes(s - wb),
        ],
        axis=1,
    )
    # at rest on the road: static deflection solves K q0 = Kt u(0)
    q0 = np.linalg.solve(lm.stiffness, lm.tyre_stiffness @ u[0, :2])
    x0 = np.concatenate([q0, np.zeros_like(q0)])
    from scipy import signal  # (as in `state_space`)

    with np.errstate(over="ignore", invalid="ignore"):
        _, y, _ = signal.lsim(state_space(lm), u, t, X0=x0)
    keep = slice(oversample, None, oversample)
    if not np.all(np.isfinite(y[keep])):  # e.g. a mass of 1e-300 kg: finite gains, NaN response
        raise VehicleError(
            f"{model.name}: its linear response overflows (stiffest mode "
            f"{highest_mode_rad_s(model):.3g} rad/s, time step {t[1]:.3g} s): the model's "
            "fields are out of range (far too stiff, too damped or too light)"
        )
    return LinearTrace(t=t[keep], accel_front=y[keep, 0], accel_rear=y[keep, 1], q=y[keep, 2:])


def _check_drive(
    model: Model, road: RoadInput, start_m: float, speed: float, n_samples: int, rate_hz: float
) -> None:
    """VehicleError unless the drive of ``n_samples`` at ``speed`` (m/s) and ``rate_hz`` from
    ``start_m`` (m) lies on ``road`` as ``simulate``'s would (``simulate.check_span``): beyond
    the road's end the road is not known, and reading it as flat returned zeros silently."""
    from vehicle.simulate import check_span  # here: simulate imports this module

    check_span(model, road, start_m, road.length_m)
    end = start_m + speed * n_samples / rate_hz
    if end > road.length_m + 1e-9:
        most = math.floor((road.length_m + 1e-9 - start_m) * rate_hz / speed)
        reach, length = distinct_texts(end, road.length_m)
        raise VehicleError(
            f"n_samples={n_samples} at speed={speed:g} m/s and rate_hz={rate_hz:g} Hz from "
            f"start_m={start_m:.6g} m take the front axle to {reach} m, past the road's end at "
            f"{length} m: allowed n_samples <= {most} (or a longer road)"
        )
