"""A progress bar of load steps on stderr: tqdm's when it is installed, else a plain one."""

from __future__ import annotations

import sys
from typing import Any

_WIDTH = 30


class StepBar:
    """Shows `done/of` load steps and the job's status; `update` redraws only on a change."""

    def __init__(self, job_id: int, enabled: bool = True):
        self.job_id = job_id
        self.enabled = enabled
        self._tqdm: Any = None
        self._last: tuple | None = None
        self._drawn = False

    def update(self, done: int, of: int, status: str) -> None:
        if not self.enabled or (done, of, status) == self._last:
            return
        self._last = (done, of, status)
        try:
            from tqdm import tqdm
        except ImportError:
            self._plain(done, of, status)
            return
        if self._tqdm is None:
            self._tqdm = tqdm(total=of, desc=f"job {self.job_id}", unit="step", file=sys.stderr)
        self._tqdm.total = of
        self._tqdm.n = done
        self._tqdm.set_postfix_str(status, refresh=False)
        self._tqdm.refresh()

    def _plain(self, done: int, of: int, status: str) -> None:
        filled = _WIDTH * done // of if of else 0
        bar = "#" * filled + "-" * (_WIDTH - filled)
        sys.stderr.write(f"\rjob {self.job_id} [{bar}] {done}/{of} steps, {status}  ")
        sys.stderr.flush()
        self._drawn = True

    def close(self) -> None:
        if self._tqdm is not None:
            self._tqdm.close()
        elif self._drawn:
            sys.stderr.write("\n")
            sys.stderr.flush()
