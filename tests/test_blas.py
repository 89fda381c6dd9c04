"""single_threaded_blas pins BLAS to one thread for the block and restores it after (_blas)."""

from __future__ import annotations

import threading

from gpsaccel._blas import blas_threads, single_threaded_blas


def test_one_thread_inside_and_the_old_count_after():
    before = blas_threads()
    with single_threaded_blas():
        assert all(n == 1 for n in blas_threads())
    assert blas_threads() == before


def test_overlapping_users_restore_only_when_the_last_one_leaves():
    before = blas_threads()
    inside, release = threading.Event(), threading.Event()

    def hold():
        with single_threaded_blas():
            inside.set()
            release.wait(5)

    t = threading.Thread(target=hold)
    t.start()
    inside.wait(5)
    with single_threaded_blas():
        pass
    assert all(n == 1 for n in blas_threads())  # the other user is still inside
    release.set()
    t.join(5)
    assert blas_threads() == before
