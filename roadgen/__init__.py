"""ISO 8608 road profiles: synthesis, tracks of segments, wheel enveloping, PSD estimate, road class."""
