"""The hostile fixtures of tests/_hostile.py for the checker's tests: ``backend`` (test_batch.py,
test_student_filter.py), ``hostile`` and ``watch``, and the machine-wide lock test_batch.py holds
with the sandbox's hostile modules (tests/sandbox/)."""

from .._hostile import (  # noqa: F401 - a conftest's names are its fixtures and hooks
    _one_hostile_module_at_a_time,
    hostile,
    pytest_generate_tests,
    watch,
)
