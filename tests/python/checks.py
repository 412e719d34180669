"""The ok/FAIL lines and the failure count shared by the Python tests (import checks; check(...);
checks.failures at the end)."""
failures = 0


def check(cond, what):
    """Prints "ok   what" or "FAIL what", counts a failure; returns cond."""
    global failures
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    failures += 0 if cond else 1
    return cond
