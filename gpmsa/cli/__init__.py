"""The ``gpmsa`` console command (``gpmsa info FILE``, ``gpmsa calibrate FILE ...``)."""
