"""Several GPM/SA models at once: shared and hierarchical calibration parameters.

See docs/models.md.
"""
