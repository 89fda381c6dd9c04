"""Hostile: in a flat class folder, imports a classmate's file and returns its answer."""
import classmate_alice  # noqa: F401  (the class folder was on sys.path before)


def kalman_filter(z):
    return classmate_alice.kalman_filter(z)
