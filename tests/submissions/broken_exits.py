"""Broken: calls sys.exit() inside the filter."""
import sys


def kalman_filter(z):
    print("giving up")
    sys.exit(3)
