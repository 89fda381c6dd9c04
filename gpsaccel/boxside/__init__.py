"""Code that runs inside a sandbox's box, imported there: the box can read it, so it holds no secret,
and the grader trusts nothing it does (the student's code runs in the same interpreter and may
replace any of it; what comes back is read against the shapes the grader declared).

It imports nothing of gpsaccel (the box may not read the checks nor the homework), only the
standard library and numpy.  :mod:`.notebook`: a graded notebook's cells and reads.
"""
