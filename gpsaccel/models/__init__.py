"""System models in course notation (Φ, Γ, H, V, W, M0): one module per system."""

from gpsaccel.models.calibration import CalibrationModel

__all__ = ["CalibrationModel"]
