"""The client against a real `mpm serve` (see conftest.py)."""

from __future__ import annotations

import io
import json
import socket
import sys
import time
import uuid
import zipfile
from pathlib import Path

import numpy as np
import pytest

from mpm_client import (
    ApiError,
    CaseError,
    Client,
    JobCancelled,
    JobFailed,
    ServerUnreachable,
    cases,
)
from mpm_client.client import extract


def test_cantilever_submit_wait_steps_step_result(client: Client, cantilever_job: int) -> None:
    job = client.job(cantilever_job)
    assert job["status"] == "succeeded"
    assert job["progress"] == {"step": 5, "of": 5}
    assert job["solve_seconds"] > 0

    reports = client.steps(cantilever_job)
    assert [r["step"] for r in reports] == [0, 1, 2, 3, 4, 5]

    first, last = client.step(cantilever_job, 0), client.step(cantilever_job, 5)
    n = 56 * 16
    assert last.step == 5 and last.load_factor == 1.0
    assert last.position.shape == (n, 2) and last.displacement.shape == (n, 2)
    assert last.stress.shape == (n, 4)
    for column in (last.volume, last.jacobian, last.plastic_strain, last.yielding, last.body):
        assert column.shape == (n,)
    assert last.yielding.dtype == bool and not last.yielding.any()  # Hencky is elastic
    assert (last.body == 0).all()
    # Each point is where it started plus its displacement (the columns are in one order).
    np.testing.assert_allclose(last.position, first.position + last.displacement, rtol=0, atol=1e-12)
    loop = last.boundaries[0]
    assert loop["polyline"].ndim == 2 and loop["polyline"].shape[1] == 2
    np.testing.assert_array_equal(loop["polyline"][0], loop["polyline"][-1])  # closed

    result = client.result(cantilever_job)
    tip = result.probes["tip"]
    assert list(tip["step"]) == [0, 1, 2, 3, 4, 5]
    assert tip["displacement"].shape == (6, 2)
    # The tip's history ends where the last step's document puts it.
    reported = next(p for p in last.report["probes"] if p["name"] == "tip")
    np.testing.assert_allclose(tip["displacement"][-1], reported["displacement"], rtol=1e-12)
    np.testing.assert_allclose(tip["position"][-1], reported["position"], rtol=1e-12)
    assert tip["displacement"][-1, 1] < 0  # the pressure on top bends it down

    # Two supports; at every step their reactions balance the applied load
    # (equilibrium to the Newton tolerance 1e-9, so 1e-6 has ample room).
    assert result.reactions.shape == (6, 2, 2)
    assert result.applied_load.shape == (6, 2)
    np.testing.assert_allclose(result.load_factor, [0, 0.2, 0.4, 0.6, 0.8, 1.0])
    for reactions, applied in zip(result.reactions[1:], result.applied_load[1:]):
        imbalance = np.linalg.norm(reactions.sum(axis=0) + applied)
        assert imbalance <= 1e-6 * np.linalg.norm(applied)
    assert result.newton_iterations[0] == 0 and (result.newton_iterations[1:] > 0).all()
    assert result.newton_iterations.sum() == job["newton_iterations"]
    # The paper's cantilever in 5 steps is solved whole: no step was cut.
    assert result.cutbacks.shape == (6,) and not result.cutbacks.any()


def test_a_3d_job_gives_3d_arrays(client: Client) -> None:
    # The built-in 3D column (128 points, 40 steps): vectors of three
    # components, the stress tensor's six, and a base that carries the
    # column's weight, rho0 g L h^2 = 390625 N, in z.
    job = client.submit(cases.example("column3d"))
    client.wait(job)
    last = client.step(job, 40)
    assert last.position.shape == (128, 3) and last.displacement.shape == (128, 3)
    assert last.stress.shape == (128, 6)
    # Its surface: the box's six faces as bicubic B-spline patches, which
    # enclose the points.
    assert len(last.boundaries) == 6
    for patch in last.boundaries:
        cu, cv = patch["cells"]
        assert patch["control_points"].shape == (3 * cv + 1, 3 * cu + 1, 3)
        assert len(patch["knots"][0]) == 3 * cu + 5 and patch["degree"] == 3
    net = np.concatenate([p["control_points"].reshape(-1, 3) for p in last.boundaries])
    assert (net.min(0) <= last.position.min(0)).all() and (net.max(0) >= last.position.max(0)).all()
    result = client.result(job)
    assert result.reactions.shape == (41, 5, 3) and result.applied_load.shape == (41, 3)
    np.testing.assert_allclose(result.reactions[-1, 4], [0, 0, 390625.0], atol=1e-6 * 390625.0)
    # The top came down about 26 m of its 50 (AMPLE's exact 25.940 m).
    assert 20.0 < last.position[:, 2].max() < 26.0


def test_to_dataframe(client: Client, cantilever_job: int) -> None:
    result = client.result(cantilever_job)
    table = result.to_dataframe()
    assert list(table.index) == [0, 1, 2, 3, 4, 5]
    for column in ("load_factor", "cutbacks", "tip.u_x", "tip.u_y", "support0.F_x", "support1.F_y", "applied.F_y"):
        assert column in table.columns
    assert table.loc[5, "tip.u_y"] == result.probes["tip"]["displacement"][-1, 1]
    assert table.loc[3, "support1.F_x"] == result.reactions[3, 1, 0]


def test_to_dataframe_without_pandas_says_what_to_install(
    client: Client, cantilever_job: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    result = client.result(cantilever_job)
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas now fails
    with pytest.raises(ImportError, match="pip install"):
        result.to_dataframe()


def test_wait_shows_progress_on_stderr(client: Client, capsys: pytest.CaptureFixture) -> None:
    job = client.submit(cases.cantilever(load_steps=2))
    client.wait(job, poll=0.05)
    assert "2/2" in capsys.readouterr().err


def test_thinned_output_gives_none_arrays(client: Client) -> None:
    case = cases.cantilever(load_steps=10)
    case["output"] = {"every": 5, "fields": ["stress"]}
    job = client.submit(case)
    client.wait(job, progress=False, timeout=300)

    thinned = client.step(job, 1)
    assert thinned.report["step"] == 1 and thinned.report["probes"]
    assert thinned.position is None and thinned.stress is None and thinned.yielding is None
    assert thinned.boundaries is None

    kept = client.step(job, 5)
    assert kept.position.shape == (896, 2) and kept.stress.shape == (896, 4)
    assert kept.displacement is None and kept.volume is None  # not in output.fields
    assert kept.boundaries


def test_invalid_case_names_the_field(client: Client) -> None:
    case = cases.cantilever()
    case["bodies"][0]["material"]["poisson_ratio"] = 0.7
    # The service's check, whatever the bundled schema catches.
    with pytest.raises(ApiError) as raised:
        client.submit(case, validate=False)
    error = raised.value
    assert (error.status, error.code) == (422, "invalid_case")
    assert error.details == {"path": "bodies[0].material.poisson_ratio"}
    assert str(error).startswith("422 invalid_case: bodies[0].material.poisson_ratio: ")


def test_local_validation_refuses_before_sending() -> None:
    # Nothing listens here: a CaseError proves the case never left.
    unreachable = Client(f"http://127.0.0.1:{_free_port()}")
    with pytest.raises(CaseError) as raised:
        unreachable.submit({**cases.cantilever(), "bodies": "beam"})
    assert raised.value.path == "bodies"
    assert str(raised.value).startswith("bodies: ")


def test_wrong_or_missing_token_is_401(server) -> None:
    for token in ("wrong", None):
        with pytest.raises(ApiError) as raised:
            Client(server.url, token=token).jobs()
        assert (raised.value.status, raised.value.code) == (401, "unauthorized")
        assert str(raised.value).startswith("401 unauthorized: ")


def test_server_down_is_server_unreachable() -> None:
    url = f"http://127.0.0.1:{_free_port()}"
    with pytest.raises(ServerUnreachable) as raised:
        Client(url, timeout=5).job(1)
    assert isinstance(raised.value, ApiError) and isinstance(raised.value, ConnectionError)
    assert url in str(raised.value) and "GET /jobs/1" in str(raised.value)
    assert raised.value.__cause__ is None and raised.value.__suppress_context__


def test_not_found_and_bad_query(client: Client) -> None:
    with pytest.raises(ApiError) as raised:
        client.job(10**9)
    assert (raised.value.status, raised.value.code) == (404, "not_found")
    with pytest.raises(ApiError) as raised:
        client.jobs(status="sleeping")
    assert (raised.value.status, raised.value.code) == (400, "bad_query")
    assert "status" in str(raised.value)


def test_failing_case_raises_job_failed_with_where(client: Client) -> None:
    case = cases.cantilever()
    case["analysis"]["newton"] = {"max_iterations": 2}
    job = client.submit(case)
    with pytest.raises(JobFailed) as raised:
        client.wait(job, progress=False, poll=0.1, timeout=600)
    failed = raised.value
    assert failed.job["id"] == job and failed.job["status"] == "failed"
    assert failed.kind == "not_converged"
    assert failed.step >= 1 and failed.iteration == 2
    assert isinstance(failed.residual, float) and failed.residual > 0
    assert failed.error["message"] and f"job {job} failed" in str(failed)


def test_cancel_and_delete(client: Client) -> None:
    # A long job (seconds a step at this size) holds the one worker.
    long = cases.cantilever(cell_size=0.25, points=(280, 80), load_steps=200)
    long["output"] = {"every": 1000}
    running = client.submit(long)
    queued = client.submit(cases.cantilever())

    assert client.cancel(queued)["status"] == "cancelled"  # at once: it never started
    with pytest.raises(JobCancelled):
        client.wait(queued, progress=False)

    _wait_for_status(client, running, "running")
    with pytest.raises(ApiError) as raised:
        client.delete(running)
    assert (raised.value.status, raised.value.code) == (409, "conflict")
    assert client.cancel(running)["cancel_requested"]
    with pytest.raises(JobCancelled) as cancelled:
        client.wait(running, progress=False, poll=0.1, timeout=300)
    assert cancelled.value.job["status"] == "cancelled"
    with pytest.raises(ApiError) as raised:
        client.cancel(running)  # ended
    assert raised.value.status == 409

    for job in (running, queued):
        client.delete(job)
        with pytest.raises(ApiError) as raised:
            client.job(job)
        assert raised.value.status == 404


def test_jobs_lists_by_status(client: Client, cantilever_job: int) -> None:
    succeeded = client.jobs(status="succeeded")
    assert cantilever_job in [j["id"] for j in succeeded]
    assert all(j["status"] == "succeeded" for j in succeeded)
    everything = [j["id"] for j in client.jobs()]
    assert everything == sorted(everything, reverse=True)  # newest first


def test_idempotency_key_returns_the_first_job(client: Client) -> None:
    key = str(uuid.uuid4())
    case = cases.cantilever(load_steps=1)
    first = client.submit(case, idempotency_key=key)
    assert client.submit(case, idempotency_key=key) == first
    with pytest.raises(ApiError) as raised:
        client.submit(cases.cantilever(load_steps=2), idempotency_key=key)
    assert raised.value.code == "idempotency_key_reused"
    client.wait(first, progress=False, timeout=300)


def test_download_unpacks_the_archive(client: Client, cantilever_job: int, tmp_path: Path) -> None:
    folder = client.download(cantilever_job, tmp_path / "run")
    assert folder == tmp_path / "run"
    for name in ("summary.json", "case.json", "points.pvd", "boundary.pvd"):
        assert (folder / name).is_file(), name
    for k in range(6):
        assert (folder / "steps" / f"step_{k:04d}.vtu").is_file()
        assert (folder / "steps" / f"step_{k:04d}_boundary.vtp").is_file()
    unpacked = json.loads((folder / "steps" / "step_0005.json").read_text())
    served = client.step(cantilever_job, 5)
    assert unpacked["report"]["step"] == 5
    np.testing.assert_allclose(unpacked["points"]["position"], served.position, rtol=1e-12)
    tip = unpacked["report"]["probes"][0]["displacement"]
    np.testing.assert_allclose(tip, served.report["probes"][0]["displacement"], rtol=1e-12)
    assert json.loads((folder / "case.json").read_text()) == client.case(cantilever_job)


ESCAPING = ["../evil.txt", "/tmp/evil.txt", "steps/../../evil.txt", "a\\..\\..\\evil.txt"]


@pytest.mark.parametrize("name", ESCAPING)
def test_extract_refuses_members_outside_the_folder(tmp_path: Path, name: str) -> None:
    archive = io.BytesIO()
    with zipfile.ZipFile(archive, "w") as zipped:
        zipped.writestr("summary.json", "{}")
        zipped.writestr(name, "escaped")
    archive.seek(0)
    folder = tmp_path / "deep" / "out"
    folder.mkdir(parents=True)
    with pytest.raises(ValueError, match="outside"):
        extract(archive, folder)
    assert list(folder.iterdir()) == []  # refused whole, nothing written
    assert not list(tmp_path.rglob("evil.txt"))


def _free_port() -> int:
    """A port nothing listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for_status(client: Client, job: int, status: str, seconds: float = 120) -> None:
    deadline = time.monotonic() + seconds
    while client.job(job)["status"] != status:
        assert time.monotonic() < deadline, f"job {job} never became {status}"
        time.sleep(0.05)
