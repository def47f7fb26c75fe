"""A dependency-free progress bar for long sweeps (stderr, shown only after a couple of seconds)."""

from __future__ import annotations

import sys
import time

__all__ = ["Progress"]

SHOW_AFTER_S = 2.0


class Progress:
    """Progress over ``total`` points with rate and ETA.

    ``enabled=None`` shows the bar only on an interactive terminal; it appears once the run has taken more
    than SHOW_AFTER_S seconds, so short sweeps stay quiet.
    """

    def __init__(self, total: int, enabled: bool | None = None, stream=None, label: str = "sweep",
                 unit: str = "points") -> None:
        self.total, self.done, self.label, self.unit = total, 0, label, unit
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self.t0 = time.perf_counter()
        self.shown = False

    def __enter__(self) -> Progress:
        return self

    def update(self, n: int) -> None:
        self.done += n
        elapsed = time.perf_counter() - self.t0
        if self.enabled and (self.shown or elapsed > SHOW_AFTER_S or self.done < self.total and elapsed > 0.5
                             and elapsed * self.total / max(self.done, 1) > SHOW_AFTER_S):
            self.shown = True
            self.stream.write("\r" + self.line(elapsed))
            self.stream.flush()

    def iterate(self, items):
        """Yield ``items``, counting each as done when the next is asked for; the bar ends with the last."""
        try:
            for item in items:
                yield item
                self.update(1)
        finally:
            self.__exit__()

    def line(self, elapsed: float) -> str:
        frac = self.done / self.total if self.total else 1.0
        rate = self.done / elapsed if elapsed > 0 else float("inf")
        eta = (self.total - self.done) / rate if rate > 0 else float("inf")
        bar = "#" * int(30 * frac)
        per_s = f"{rate:,.0f} pts/s" if self.unit == "points" else f"{rate:,.2g} {self.unit}/s"
        return (f"{self.label} [{bar:<30}] {100 * frac:5.1f}% {self.done}/{self.total} {self.unit} "
                f"{per_s} ETA {eta:6.1f} s")

    def __exit__(self, *exc) -> None:
        if self.shown:
            self.shown = False
            self.stream.write("\n")
            self.stream.flush()
