"""The package's version, written here only: ``gpsaccel.__version__``, ``gpsaccel --version`` and
the wheel's metadata (``pyproject.toml`` reads it with ``attr:``) all come from this line."""

__version__ = "0.1.0"
