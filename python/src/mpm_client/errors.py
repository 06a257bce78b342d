"""The exceptions the client raises.

`ApiError` is every error answer of the service (body
`{"error": {"code", "message", "details"}}`); `ServerUnreachable` is a
service that does not answer at all. `JobFailed` and `JobCancelled` are jobs
that ended without a result, `CaseError` a case refused before it was sent.
"""

from __future__ import annotations

from typing import Any


class ApiError(Exception):
    """An error answer of the service.

    Attributes: `status` (HTTP status, None when there was no answer), `code`
    (e.g. `invalid_case`, `unauthorized`, `not_found`), `message` and
    `details` (e.g. `{"path": "bodies[0].material.poisson_ratio"}` for an
    invalid case, `{"parameter": "status"}` for a bad query).
    """

    def __init__(self, status: int | None, code: str, message: str, details: Any = None):
        super().__init__(status, code, message, details)
        self.status = status
        self.code = code
        self.message = message
        self.details = details

    @property
    def field(self) -> str | None:
        """The field, query parameter or header the error names, if any."""
        if isinstance(self.details, dict):
            for key in ("path", "parameter", "header"):
                if isinstance(self.details.get(key), str):
                    return self.details[key]
        return None

    def __str__(self) -> str:
        message = self.message
        field = self.field
        if field and field not in message:
            message = f"{field}: {message}"
        return f"{self.status} {self.code}: {message}"


class ServerUnreachable(ApiError, ConnectionError):
    """No answer from the service: refused, reset, timed out or unresolvable.

    Catch it as `ApiError` or as `ConnectionError`; `url` is what was asked.
    """

    def __init__(self, url: str, reason: str, request: str = ""):
        where = f" ({request})" if request else ""
        super().__init__(None, "unreachable", f"cannot reach the mpm service at {url}{where}: {reason}")
        self.url = url
        self.reason = reason

    def __str__(self) -> str:
        return self.message


class JobFailed(RuntimeError):
    """A job that ended `failed`.

    `job` is the final job document; `error` its error dict with `kind`
    (e.g. `not_converged`, `diverged`, `time_limit`), `message`, and where the
    solver failed: `step` (load step), `iteration` (Newton iteration) and
    `residual` (the last relative residual; absent when none was computed).
    """

    def __init__(self, job: dict):
        self.job = job
        self.error: dict = job.get("error") or {}
        super().__init__(f"job {job.get('id')} failed: {self.error.get('message', 'no reason given')}")

    @property
    def kind(self) -> str | None:
        return self.error.get("kind")

    @property
    def step(self) -> int | None:
        return self.error.get("step")

    @property
    def iteration(self) -> int | None:
        return self.error.get("iteration")

    @property
    def residual(self) -> float | None:
        return self.error.get("residual")


class JobCancelled(RuntimeError):
    """A job that ended `cancelled`; `job` is its final document (its finished steps stay readable)."""

    def __init__(self, job: dict):
        self.job = job
        done = (job.get("progress") or {}).get("step")
        super().__init__(f"job {job.get('id')} was cancelled after {done} load steps")


class CaseError(ValueError):
    """A case that does not match the bundled JSON Schema.

    `path` is the JSON path of the first error, as the service writes it
    (`bodies[0].material.poisson_ratio`; `$` for the case itself).
    """

    def __init__(self, path: str, message: str):
        super().__init__(f"{path}: {message}")
        self.path = path
        self.message = message
