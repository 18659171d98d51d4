"""The time limit of a B-Rep build (:func:`~igl_heatseg.cad.build.build_brep`'s
``time_limit``): whether it has passed, what it made the build skip, and its report."""

from __future__ import annotations

import logging
import time

logger = logging.getLogger(__name__)

__all__ = ["TimeLimit"]


class TimeLimit:
    """Seconds a build may start new work in, counted from construction (None: no limit).

    Examples
    --------
    >>> limit = TimeLimit(0.0)
    >>> limit.out_of_time("rebuild 1"), limit.left(), limit.note("open shell")
    (True, 0.0, 'open shell; time limit reached: skipped rebuild 1')
    >>> limit.report()
    {'seconds': 0.0, 'reached': True, 'skipped': ['rebuild 1']}
    >>> TimeLimit(None).out_of_time("anything"), TimeLimit(None).report()
    (False, None)
    """

    def __init__(self, seconds: float | None):
        self.seconds = None if seconds is None else float(seconds)
        self.deadline = None if seconds is None else time.perf_counter() + self.seconds
        self.skipped: list[str] = []

    def left(self) -> float | None:
        """Seconds left (>= 0), None without a limit."""
        return None if self.deadline is None else max(self.deadline - time.perf_counter(), 0.0)

    def out_of_time(self, what: str) -> bool:
        """Whether the limit has passed; if so, ``what`` (work not started) is noted."""
        if self.deadline is None or time.perf_counter() < self.deadline:
            return False
        logger.warning("time limit reached: %s is not started", what)
        self.skipped.append(what)
        return True

    def note(self, message: str) -> str:
        """``message`` with what the limit skipped appended (as it is when nothing was)."""
        if not self.skipped:
            return message
        note = "time limit reached: skipped " + "; ".join(self.skipped)
        return f"{message}; {note}" if message else note

    def report(self) -> dict | None:
        """``seconds``, ``reached`` and ``skipped``; None without a limit."""
        if self.seconds is None:
            return None
        return {"seconds": self.seconds, "reached": bool(self.skipped),
                "skipped": list(self.skipped)}
