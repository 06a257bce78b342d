"""Python client of the mpm job service (implicit material point method).

    from mpm_client import Client, cases
    client = Client("http://127.0.0.1:8080", token="...")
    job = client.submit(cases.cantilever())
    client.wait(job)
    tip = client.result(job).probes["tip"]["displacement"][-1]   # m

Units are SI throughout: m, Pa, N per metre of thickness, s.
"""

from . import cases
from .client import Client, Result, Step
from .errors import ApiError, CaseError, JobCancelled, JobFailed, ServerUnreachable

__version__ = "0.1.0"

__all__ = [
    "Client",
    "Step",
    "Result",
    "cases",
    "ApiError",
    "ServerUnreachable",
    "JobFailed",
    "JobCancelled",
    "CaseError",
]
