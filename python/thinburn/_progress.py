"""A dependency-free progress bar for long work on the terminal."""
from __future__ import annotations

import sys
import time


class Progress:
    """Draws `label [#####-----]  45%  27/60  extra` on one line (stderr).

    On a terminal the line is redrawn in place; elsewhere (CI logs) it prints at every 10 %.
    """

    def __init__(self, total: int, label: str = "", stream=None, width: int = 30):
        self.total = max(1, int(total))
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.width = width
        self.start = time.perf_counter()
        self._last_decile = -1
        self._tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def update(self, done: int, extra: str = "") -> None:
        frac = min(1.0, done / self.total)
        filled = int(round(frac * self.width))
        elapsed = time.perf_counter() - self.start
        eta = elapsed / frac - elapsed if frac > 0 else float("nan")
        line = (f"{self.label} [{'#' * filled}{'-' * (self.width - filled)}] {100 * frac:5.1f}%"
                f"  {done}/{self.total}  {elapsed:6.1f}s elapsed, ~{eta:5.1f}s left  {extra}")
        if self._tty:
            self.stream.write("\r" + line)
            if done >= self.total:
                self.stream.write("\n")
        else:
            decile = int(frac * 10)
            if decile == self._last_decile:
                return
            self._last_decile = decile
            self.stream.write(line + "\n")
        self.stream.flush()
