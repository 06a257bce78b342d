"""The HTTP client of the mpm job service (standard library urllib only).

Units are the solver's SI units: positions and displacements in m, stresses
and pressures in Pa, forces (reactions, applied loads) in N per metre of
thickness, times in s.
"""

from __future__ import annotations

import http.client
import json
import os
import shutil
import tempfile
import time
import urllib.error
import urllib.parse
import urllib.request
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import cases
from .errors import ApiError, JobCancelled, JobFailed, ServerUnreachable
from .progress import StepBar

__all__ = ["Client", "Step", "Result"]

_ENDED = ("succeeded", "failed", "cancelled")
_PAGE = 500  # the service's largest page of GET /jobs
# `Client.wait`'s pauses: the first (s), and the growth of each next one up
# to its `poll`. A job is then seen ending at most a quarter of its time
# late; a poll costs the server about a millisecond.
_FIRST_PAUSE = 0.01
_PAUSE_GROWTH = 1.25

# A step document's point columns and the shape of one point's entry, in
# plane strain and in 3D (`analysis.type: "3d"`: vectors of three, the
# stress tensor's six components).
_COLUMNS: dict[str, tuple] = {
    "position": (float, 2, 3),
    "displacement": (float, 2, 3),
    "stress": (float, 4, 6),
    "volume": (float, None, None),
    "jacobian": (float, None, None),
    "plastic_strain": (float, None, None),
    "yielding": (bool, None, None),
    "body": (np.int64, None, None),
}


def _array(values: list, dtype: Any, width: int | None) -> np.ndarray:
    """A column as an (n,) or (n, width) array; (0,) or (0, width) when empty."""
    array = np.asarray(values, dtype=dtype)
    return array.reshape(-1, width) if width else array.reshape(-1)


def _column(values: list | None, dtype: Any, width: int | None) -> np.ndarray | None:
    return None if values is None else _array(values, dtype, width)


def _dimension(vectors: list) -> int:
    """2 or 3: the components of a list of vectors (2 when it is empty)."""
    return len(vectors[0]) if vectors else 2


@dataclass
class Step:
    """One stored load step (step 0 is the undeformed state).

    `report`: the step report (load factor, Newton, probes, reactions,
    timings). Point arrays, n material points, each None when the service did
    not store that column (the case's `output.fields`) or the step's points
    at all (`output.every`): `position`, `displacement` (n, 2) m; `stress`
    (n, 4) Cauchy [xx, yy, xy, zz] Pa; `volume` (n,) current, m^2 per m;
    `jacobian` (n,) det F; `plastic_strain` (n,) accumulated; `yielding` (n,)
    bool, flowed plastically in the step; `body` (n,) body index. A 3D
    case's: `position`, `displacement` (n, 3) m, `stress` (n, 6) Cauchy [xx,
    yy, zz, xy, yz, xz] Pa, `volume` m^3.
    `boundaries`: per closed loop of outer points a dict with `body`, `hole`,
    `points` (indices), `bspline` (`degree`, `knots`, `control_points` (k, 2)
    m) and `polyline` (m, 2) m; None when the step's points are not stored.
    In 3D, per face patch of a body's surface a dict with `body`, `cells`
    (2,), `closed` (2,) bool, `degree` 3, `knots` (two arrays) and
    `control_points` (3 cells_v + 1, 3 cells_u + 1, 3) m: a bicubic B-spline
    whose cells are Bezier patches (`net[3l:3l+4, 3k:3k+4]` is cell (k, l)'s).
    """

    report: dict
    position: np.ndarray | None = None
    displacement: np.ndarray | None = None
    stress: np.ndarray | None = None
    volume: np.ndarray | None = None
    jacobian: np.ndarray | None = None
    plastic_strain: np.ndarray | None = None
    yielding: np.ndarray | None = None
    body: np.ndarray | None = None
    boundaries: list[dict] | None = None

    @property
    def step(self) -> int:
        return self.report["step"]

    @property
    def load_factor(self) -> float:
        return self.report["load_factor"]

    @classmethod
    def from_json(cls, document: Mapping[str, Any]) -> Step:
        points = document.get("points") or {}
        solid = _dimension(points.get("position") or []) == 3
        arrays = {
            name: _column(points.get(name), dtype, solid_width if solid else width)
            for name, (dtype, width, solid_width) in _COLUMNS.items()
        }
        boundaries = document.get("boundaries")
        if boundaries is not None:
            boundaries = [_surface(b) if "cells" in b else _boundary(b) for b in boundaries]
        return cls(report=document["report"], boundaries=boundaries, **arrays)


def _surface(patch: Mapping[str, Any]) -> dict:
    patch = dict(patch)
    cu, cv = patch["cells"]
    net = _array(patch.get("control_points", []), float, 3)
    patch["control_points"] = net.reshape(3 * cv + 1, 3 * cu + 1, 3)
    patch["cells"] = np.asarray(patch["cells"], dtype=np.int64)
    patch["closed"] = np.asarray(patch["closed"], dtype=bool)
    patch["knots"] = [np.asarray(k, dtype=float) for k in patch["knots"]]
    return patch


def _boundary(loop: Mapping[str, Any]) -> dict:
    loop = dict(loop)
    loop["polyline"] = _array(loop.get("polyline", []), float, 2)
    loop["points"] = _array(loop.get("points", []), np.int64, None)
    if loop.get("bspline"):
        spline = dict(loop["bspline"])
        spline["knots"] = _array(spline.get("knots", []), float, None)
        spline["control_points"] = _array(spline.get("control_points", []), float, 2)
        loop["bspline"] = spline
    return loop


@dataclass
class Result:
    """Histories of a job's finished steps, one entry per step from step 0.

    `steps` (k,) step numbers; `load_factor` (k,); `applied_load` (k, 2) N/m,
    the resultant of the loads applied; `reactions` (k, supports, 2) N/m, the
    supports' reactions in the case's order (they balance `applied_load`;
    in 3D (k, 3) and (k, supports, 3) N);
    `newton_iterations` (k,), and `cutbacks` (k,) the tries each step
    failed and cut (0 where a server before them gives none); `probes` {name: {"step" (k,), "load_factor"
    (k,), "position" (k, 2) m, "displacement" (k, 2) m}}; `timings` summed
    wall seconds per stage; `job` the job document; `raw` the response.
    """

    job: dict
    steps: np.ndarray
    load_factor: np.ndarray
    applied_load: np.ndarray
    reactions: np.ndarray
    newton_iterations: np.ndarray
    cutbacks: np.ndarray
    probes: dict[str, dict[str, np.ndarray]]
    timings: dict
    raw: dict = field(repr=False)

    @classmethod
    def from_json(cls, document: Mapping[str, Any]) -> Result:
        reactions = document.get("reactions", [])
        supports = len(reactions[0]["supports"]) if reactions else 0
        dimension = _dimension([r["applied_load"] for r in reactions])
        probes = {
            name: {
                "step": np.array([s["step"] for s in history], dtype=np.int64),
                "load_factor": np.array([s["load_factor"] for s in history], dtype=float),
                "position": _array([s["position"] for s in history], float, 2),
                "displacement": _array([s["displacement"] for s in history], float, 2),
            }
            for name, history in document.get("probes", {}).items()
        }
        newton = {n["step"]: n for n in document.get("newton", [])}
        steps = np.array([r["step"] for r in reactions], dtype=np.int64)
        return cls(
            job=document.get("job", {}),
            steps=steps,
            load_factor=np.array([r["load_factor"] for r in reactions], dtype=float),
            applied_load=_array([r["applied_load"] for r in reactions], float, dimension),
            reactions=np.array([r["supports"] for r in reactions], dtype=float).reshape(
                len(reactions), supports, dimension
            ),
            newton_iterations=np.array(
                [newton.get(int(s), {}).get("iterations", 0) for s in steps], dtype=np.int64
            ),
            cutbacks=np.array(
                [newton.get(int(s), {}).get("cutbacks", 0) for s in steps], dtype=np.int64
            ),
            probes=probes,
            timings=document.get("timings", {}),
            raw=dict(document),
        )

    def to_dataframe(self) -> Any:
        """A pandas DataFrame, one row per step (index `step`).

        Columns: `load_factor`, `newton_iterations`, `cutbacks`, `applied.F_x`,
        `applied.F_y` (N/m), per probe `NAME.x`, `NAME.y` (position, m) and
        `NAME.u_x`, `NAME.u_y` (displacement, m), per support `supportI.F_x`,
        `supportI.F_y` (reaction, N/m).
        """
        try:
            import pandas as pd
        except ImportError:
            raise ImportError(
                "Result.to_dataframe needs pandas: pip install 'mpm-client[pandas]'"
            ) from None
        table = pd.DataFrame(
            {
                "load_factor": self.load_factor,
                "newton_iterations": self.newton_iterations,
                "cutbacks": self.cutbacks,
                "applied.F_x": self.applied_load[:, 0],
                "applied.F_y": self.applied_load[:, 1],
            },
            index=pd.Index(self.steps, name="step"),
        )
        for name, probe in self.probes.items():
            columns = {
                f"{name}.x": probe["position"][:, 0],
                f"{name}.y": probe["position"][:, 1],
                f"{name}.u_x": probe["displacement"][:, 0],
                f"{name}.u_y": probe["displacement"][:, 1],
            }
            table = table.join(pd.DataFrame(columns, index=pd.Index(probe["step"], name="step")))
        for i in range(self.reactions.shape[1]):
            table[f"support{i}.F_x"] = self.reactions[:, i, 0]
            table[f"support{i}.F_y"] = self.reactions[:, i, 1]
        return table


class Client:
    """A connection to one mpm service.

    url: the service's base URL, e.g. `http://127.0.0.1:8080`. token: the
    service's `--token`, sent as `Authorization: Bearer TOKEN`. timeout:
    seconds to wait for each HTTP answer.
    """

    def __init__(self, url: str, token: str | None = None, timeout: float = 30):
        self.url = url.rstrip("/")
        self.token = token
        self.timeout = timeout

    def __repr__(self) -> str:
        return f"Client({self.url!r})"

    # --- HTTP -------------------------------------------------------------

    def _open(
        self,
        method: str,
        path: str,
        body: bytes | None = None,
        headers: Mapping[str, str] | None = None,
        query: Mapping[str, Any] | None = None,
        timeout: float | None = None,
    ) -> http.client.HTTPResponse:
        url = self.url + path
        if query:
            url += "?" + urllib.parse.urlencode({k: v for k, v in query.items() if v is not None})
        request = urllib.request.Request(url, data=body, method=method)
        request.add_header("Accept", "application/json")
        request.add_header("User-Agent", "mpm-client")
        if body is not None:
            request.add_header("Content-Type", "application/json")
        if self.token:
            request.add_header("Authorization", f"Bearer {self.token}")
        for name, value in (headers or {}).items():
            request.add_header(name, value)
        try:
            return urllib.request.urlopen(request, timeout=timeout or self.timeout)
        except urllib.error.HTTPError as e:
            try:
                data = self._read(e, f"{method} {path}")
            finally:
                e.close()
            raise _api_error(e.code, data) from None
        except urllib.error.URLError as e:
            raise ServerUnreachable(self.url, self._describe(e.reason), f"{method} {path}") from None
        except (OSError, http.client.HTTPException) as e:
            raise ServerUnreachable(self.url, self._describe(e), f"{method} {path}") from None

    def _read(self, response: Any, request: str) -> bytes:
        try:
            return response.read()
        except (OSError, http.client.HTTPException) as e:
            raise ServerUnreachable(self.url, self._describe(e), request) from None

    def _describe(self, reason: Any) -> str:
        """Why there was no answer, in words (a timeout says how long it waited)."""
        if isinstance(reason, TimeoutError) or "timed out" in str(reason):
            return f"no answer within {self.timeout} s"
        return str(reason) or type(reason).__name__

    def _json(self, method: str, path: str, **kwargs: Any) -> Any:
        with self._open(method, path, **kwargs) as response:
            data = self._read(response, f"{method} {path}")
        return json.loads(data) if data else None

    # --- jobs -------------------------------------------------------------

    def submit(
        self,
        case: Mapping[str, Any] | str | os.PathLike,
        idempotency_key: str | None = None,
        validate: bool = True,
    ) -> int:
        """Queue a case (a dict, or the path of a JSON file); returns the job id.

        The case is checked against the bundled schema first (`CaseError`,
        naming the field; `validate=False` skips that), then by the service
        (`ApiError` 422 naming the field in `details.path`). With an
        `idempotency_key` (1 to 255 visible ASCII characters, e.g. a UUID) a
        retry of a submission whose answer was lost, with the same key and
        the same case, returns the job the first one made instead of a new one.
        """
        document = case if isinstance(case, Mapping) else json.loads(Path(case).read_text(encoding="utf-8"))
        if validate:
            cases.validate(document)
        headers = {"Idempotency-Key": idempotency_key} if idempotency_key else None
        body = json.dumps(document).encode("utf-8")
        return int(self._json("POST", "/jobs", body=body, headers=headers)["id"])

    def job(self, id: int) -> dict:
        """The job: `status`, `progress` {step, of}, `solve_seconds`, `error`, times."""
        return self._json("GET", f"/jobs/{int(id)}")

    def jobs(self, status: str | None = None) -> list[dict]:
        """Every job, newest first; with `status` (queued, running, succeeded, failed,
        cancelled) only those."""
        found: list[dict] = []
        while True:
            page = self._json(
                "GET", "/jobs", query={"status": status, "limit": _PAGE, "offset": len(found)}
            )
            found.extend(page["jobs"])
            if not page["jobs"] or len(found) >= page["total"]:
                return found

    def case(self, id: int) -> dict:
        """The case as submitted."""
        return self._json("GET", f"/jobs/{int(id)}/case")

    def wait(
        self, id: int, progress: bool = True, poll: float = 0.5, timeout: float | None = None
    ) -> dict:
        """Poll the job until it ends; returns the final job.

        poll: the longest pause between polls, s; the first pauses are
        shorter (10 ms, growing by a quarter each time up to `poll`), so a
        job is seen ending within about a quarter of its time, and one of a
        few tens of milliseconds is not kept waiting half a second.
        progress: show load steps done/of on stderr. timeout: give up after
        this many seconds with `TimeoutError` (the job goes on). Raises
        `JobFailed` (with the job's error: kind, message, step, iteration,
        residual) or `JobCancelled` when the job ends so.
        """
        deadline = None if timeout is None else time.monotonic() + timeout
        pause = min(poll, _FIRST_PAUSE)
        bar = StepBar(int(id), enabled=progress)
        try:
            while True:
                job = self.job(id)
                bar.update(job["progress"]["step"], job["progress"]["of"], job["status"])
                if job["status"] in _ENDED:
                    break
                if deadline is not None and time.monotonic() >= deadline:
                    raise TimeoutError(f"job {id} is still {job['status']} after {timeout} s")
                time.sleep(pause)
                pause = min(poll, _PAUSE_GROWTH * pause)
        finally:
            bar.close()
        if job["status"] == "failed":
            raise JobFailed(job)
        if job["status"] == "cancelled":
            raise JobCancelled(job)
        return job

    def cancel(self, id: int) -> dict:
        """Cancel a job; returns it. A queued job ends at once; a running one
        stops at its next Newton iteration (`cancel_requested` true). An
        ended job is `ApiError` 409."""
        return self._json("POST", f"/jobs/{int(id)}/cancel")

    def delete(self, id: int) -> None:
        """Delete an ended job and its results (a queued or running one is `ApiError` 409)."""
        with self._open("DELETE", f"/jobs/{int(id)}"):
            pass

    # --- results ----------------------------------------------------------

    def steps(self, id: int) -> list[dict]:
        """The step reports so far, from step 0 (the undeformed state)."""
        return self._json("GET", f"/jobs/{int(id)}/steps")["steps"]

    def step(self, id: int, k: int) -> Step:
        """Step `k`'s report, point arrays and boundary curves (see `Step`)."""
        return Step.from_json(self._json("GET", f"/jobs/{int(id)}/steps/{int(k)}"))

    def result(self, id: int) -> Result:
        """Probe histories, reactions, applied loads, Newton statistics and timings (see `Result`)."""
        return Result.from_json(self._json("GET", f"/jobs/{int(id)}/result"))

    def download(self, id: int, folder: str | os.PathLike, timeout: float = 600.0) -> Path:
        """Fetch the job's archive and unpack it into `folder` (made if missing).

        The server builds the whole zip before it answers (one at a time),
        so a large job may take a while: `timeout` (s) bounds that wait.

        The layout `mpm run --out DIR` writes: `summary.json`, `case.json`,
        `points.pvd`, `boundary.pvd` and `steps/step_NNNN.{json,vtu}`,
        `steps/step_NNNN_boundary.vtp`. Returns the folder. An archive with
        a member that would land outside the folder is refused whole
        (`ValueError`) before anything is written.
        """
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile() as archive:
            with self._open("GET", f"/jobs/{int(id)}/archive", timeout=timeout) as response:
                try:
                    shutil.copyfileobj(response, archive)
                except (OSError, http.client.HTTPException) as e:
                    raise ServerUnreachable(self.url, self._describe(e), f"GET /jobs/{id}/archive") from None
            archive.seek(0)
            extract(archive, folder)
        return folder


def extract(archive: Any, folder: Path) -> None:
    """Unpack a zip (path or file object) into `folder`, refusing members that would escape it."""
    root = folder.resolve()
    with zipfile.ZipFile(archive) as zipped:
        for member in zipped.infolist():
            name = member.filename.replace("\\", "/")
            target = (root / name).resolve()
            if name.startswith("/") or ".." in name.split("/") or not target.is_relative_to(root):
                raise ValueError(f"archive member {member.filename!r} would be written outside {folder}")
        zipped.extractall(root)


def _api_error(status: int, data: bytes) -> ApiError:
    """The service's `{"error": {code, message, details}}`, or whatever a proxy answered."""
    try:
        error = json.loads(data)["error"]
        return ApiError(status, error["code"], error["message"], error.get("details"))
    except (ValueError, KeyError, TypeError):
        text = data.decode("utf-8", "replace").strip()[:200]
        return ApiError(status, "http_error", text or http.client.responses.get(status, "error"))
