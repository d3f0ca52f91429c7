"""Progress of long loops: a tqdm bar on a terminal, a plain line every ~10 s otherwise.

One small reporter serves every long loop (sweeps, reproduce steps, continuation): the caller
says what runs (``label``) and how many units of work there are (points, steps, ...), then
calls :meth:`Progress.update` as work finishes.

* ``stderr`` is a terminal: a tqdm bar labelled ``label`` counting units (it appears only after
  ``delay`` seconds, so short loops stay silent).
* otherwise (a log file, a pipe, CI): one plain line every ``interval`` seconds, e.g.
  ``basin noncollocated e=0.1: 12000/40000 points (30%), 31 s elapsed, ~72 s left``, and a final
  line if the loop ran for at least ``delay`` seconds.
* ``enabled=False`` (the CLI's ``--quiet``): nothing at all.

Nothing is ever written to stdout.
"""
from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from typing import Any, TextIO

__all__ = ["Progress"]


def _fmt_seconds(s: float) -> str:
    if not math.isfinite(s):
        return "?"
    if s < 100:
        return f"{s:.0f} s"
    if s < 6000:
        return f"{s / 60:.1f} min"
    return f"{s / 3600:.1f} h"


class Progress:
    """Context-managed progress reporter for a loop of `total` units of work.

    Parameters
    ----------
    total : int
        Units of work in the whole loop (>= 0).
    label : str
        What runs, e.g. ``"basin noncollocated e=0.1"`` (the bar's description).
    enabled : bool, default True
        False silences the reporter completely.
    unit : str, default "point"
        Name of one unit (plural formed by appending "s" in the plain lines).
    initial : int, default 0
        Units already done (e.g. resumed from a store).
    file : text stream, optional
        Where to report; default ``sys.stderr`` (looked up when the reporter starts).
    interval : float, default 10.0
        Seconds between plain lines when `file` is not a terminal.
    delay : float, default 2.0
        Seconds before anything is shown: the tqdm bar appears after `delay`, and the final
        plain line is written only if the loop lasted at least `delay` (or a line was
        already written).
    clock : callable, default time.monotonic
        Returns seconds; replaceable for tests.

    Examples
    --------
    >>> import io
    >>> out = io.StringIO()                      # not a terminal: plain lines
    >>> t = iter([0.0, 11.0, 30.0])              # a fake clock: start, update, close
    >>> with Progress(100, "demo", file=out, clock=lambda: next(t)) as p:
    ...     p.update(40)
    >>> print(out.getvalue(), end="")
    demo: 40/100 points (40%), 11 s elapsed, ~16 s left
    demo: stopped at 40/100 points after 30 s
    """

    def __init__(self, total: int, label: str, *, enabled: bool = True, unit: str = "point",
                 initial: int = 0, file: TextIO | None = None, interval: float = 10.0,
                 delay: float = 2.0, clock: Callable[[], float] = time.monotonic):
        if isinstance(total, bool) or not isinstance(total, int) or total < 0:
            raise ValueError(f"total must be a non-negative integer, got {total!r}")
        if not isinstance(label, str):
            raise ValueError(f"label must be a string, got {label!r}")
        if not isinstance(enabled, bool):
            raise ValueError(f"enabled must be True or False, got {enabled!r}")
        if isinstance(initial, bool) or not isinstance(initial, int) or not 0 <= initial <= total:
            raise ValueError(f"initial must be an integer in [0, total={total}], got {initial!r}")
        for name, v in (("interval", interval), ("delay", delay)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not v >= 0:
                raise ValueError(f"{name} must be a non-negative number of seconds, got {v!r}")
        self.total, self.label, self.enabled, self.unit = total, label, enabled, unit
        self.n = self._n0 = initial
        self.file, self.interval, self.delay, self.clock = file, float(interval), float(delay), clock
        self._bar: Any = None
        self._t0 = self._last = 0.0
        self._printed = False
        self._open = False

    def __enter__(self):
        if not self.enabled:
            return self
        self._open = True
        if self.file is None:
            self.file = sys.stderr
        isatty = getattr(self.file, "isatty", None)
        if isatty is not None and isatty():
            from tqdm.auto import tqdm  # imported only when a bar is actually shown

            self._bar = tqdm(total=self.total, initial=self.n, desc=self.label, unit=self.unit,
                             file=self.file, delay=self.delay, dynamic_ncols=True)
        else:
            self._t0 = self._last = self.clock()
        return self

    def update(self, n: int = 1) -> None:
        """Record `n` more units done."""
        self.n += int(n)
        if not self._open:
            return
        if self._bar is not None:
            self._bar.update(int(n))
            return
        now = self.clock()
        if now - self._last >= self.interval:
            self._last = now
            self._line(now)

    def _line(self, now: float) -> None:
        elapsed = now - self._t0
        pct = 100.0 * self.n / self.total if self.total else 100.0
        done_here = self.n - self._n0
        left = (self.total - self.n) * elapsed / done_here if done_here > 0 else math.inf
        self._write(f"{self.label}: {self.n}/{self.total} {self.unit}s ({pct:.0f}%), "
                    f"{_fmt_seconds(elapsed)} elapsed, ~{_fmt_seconds(left)} left")

    def _write(self, text: str) -> None:
        self.file.write(text + "\n")
        self.file.flush()
        self._printed = True

    def close(self) -> None:
        """Finish the bar, or write the final plain line (see `delay`)."""
        if not self._open:
            return
        self._open = False
        if self._bar is not None:
            self._bar.close()
            return
        elapsed = self.clock() - self._t0
        if self._printed or elapsed >= self.delay:
            if self.n >= self.total:
                self._write(f"{self.label}: {self.n}/{self.total} {self.unit}s done in "
                            f"{_fmt_seconds(elapsed)}")
            else:
                self._write(f"{self.label}: stopped at {self.n}/{self.total} {self.unit}s "
                            f"after {_fmt_seconds(elapsed)}")

    def __exit__(self, *exc) -> None:
        self.close()
