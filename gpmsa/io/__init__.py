"""The emulator file (``*.gpmsa``): a zip of .npy arrays plus a JSON manifest, read safely."""
