"""A real `mpm serve` for the session: port 0, a temporary SQLite database, a token.

The binary is $MPM_BIN, else ../target/debug/mpm beside this python/ folder.
"""

from __future__ import annotations

import os
import re
import subprocess
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from mpm_client import Client, cases

PYTHON_DIR = Path(__file__).resolve().parents[1]
TOKEN = "python-client-test-token"
START_SECONDS = 60


@dataclass
class Server:
    binary: Path
    url: str
    token: str


def mpm_binary() -> Path:
    binary = Path(os.environ.get("MPM_BIN", PYTHON_DIR / ".." / "target" / "debug" / "mpm"))
    binary = binary.resolve()
    if not binary.is_file():
        pytest.fail(f"no mpm binary at {binary}: build it, or set MPM_BIN", pytrace=False)
    return binary


@pytest.fixture(scope="session")
def binary() -> Path:
    return mpm_binary()


@pytest.fixture(scope="session")
def server(binary: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    folder = tmp_path_factory.mktemp("mpm-serve")
    stdout, stderr = folder / "stdout", folder / "stderr"
    command = [
        str(binary), "serve",
        "--addr", "127.0.0.1:0",
        "--database", str(folder / "jobs.sqlite"),
        "--token", TOKEN,
        "--workers", "1",
    ]
    with stdout.open("wb") as out, stderr.open("wb") as err:
        process = subprocess.Popen(command, stdout=out, stderr=err, stdin=subprocess.DEVNULL)
    try:
        url = _announced_url(process, stdout, stderr)
        yield Server(binary=binary, url=url, token=TOKEN)
    finally:
        process.terminate()  # SIGTERM: a clean shutdown
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def _announced_url(process: subprocess.Popen, stdout: Path, stderr: Path) -> str:
    """The URL of the first stdout line, "listening on http://ADDR (...)"."""
    deadline = time.monotonic() + START_SECONDS
    while time.monotonic() < deadline:
        text = stdout.read_text(errors="replace")
        if "\n" in text:
            match = re.match(r"listening on (http://\S+)", text)
            if not match:
                pytest.fail(f"mpm serve's first line is not its address: {text.splitlines()[0]!r}")
            return match.group(1)
        if process.poll() is not None:
            pytest.fail(f"mpm serve exited with {process.returncode}: {stderr.read_text(errors='replace')}")
        time.sleep(0.05)
    pytest.fail(f"mpm serve did not announce its address within {START_SECONDS} s")


@pytest.fixture(scope="session")
def client(server: Server) -> Client:
    return Client(server.url, token=server.token)


@pytest.fixture(scope="session")
def cantilever_job(client: Client) -> int:
    """The paper's cantilever, solved once for the tests that read its results."""
    job = client.submit(cases.cantilever())
    client.wait(job, progress=False, timeout=300)
    return job
