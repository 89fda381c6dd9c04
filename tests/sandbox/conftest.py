"""The hostile fixtures of tests/_hostile.py for the sandbox's tests: ``backend``, ``hostile`` and
``watch``, and the machine-wide lock the hostile modules hold with tests/check/test_batch.py."""

from .._hostile import (  # noqa: F401 - a conftest's names are its fixtures and hooks
    _one_hostile_module_at_a_time,
    backend,
    hostile,
    pytest_generate_tests,
    watch,
    zygotes,
)
