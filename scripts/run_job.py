#!/usr/bin/env python3
"""Submit a case to the mpm service, wait for it, and fetch its last step.

Standard library only. Usage:
    python3 scripts/run_job.py CASE.json [--url http://127.0.0.1:8080] [--token T]
Prints the job's final state and the probe histories; writes last_step.json.
"""
import argparse
import json
import sys
import time
import urllib.error
import urllib.request


def call(url, token, method="GET", body=None):
    req = urllib.request.Request(url, method=method, data=body)
    if body is not None:
        req.add_header("Content-Type", "application/json")
    if token:
        req.add_header("Authorization", f"Bearer {token}")
    try:
        with urllib.request.urlopen(req) as resp:
            return json.load(resp)
    except urllib.error.HTTPError as e:
        error = json.load(e)["error"]
        sys.exit(f"{e.code} {error['code']}: {error['message']}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("case")
    parser.add_argument("--url", default="http://127.0.0.1:8080")
    parser.add_argument("--token")
    args = parser.parse_args()

    with open(args.case, "rb") as f:
        job = call(f"{args.url}/jobs", args.token, "POST", f.read())
    print(f"job {job['id']} queued")
    while job["status"] in ("queued", "running"):
        time.sleep(0.2)
        job = call(f"{args.url}/jobs/{job['id']}", args.token)
        print(f"  {job['status']}: step {job['progress']['step']} of {job['progress']['of']}", end="\r")
    print()
    print(json.dumps({k: job[k] for k in ("status", "solve_seconds", "newton_iterations", "error")}, indent=2))
    if job["status"] != "succeeded":
        sys.exit(1)
    result = call(f"{args.url}/jobs/{job['id']}/result", args.token)
    for name, history in result["probes"].items():
        for sample in history:
            print(f"{name} step {sample['step']}: displacement {sample['displacement']}")
    last = job["progress"]["of"]
    step = call(f"{args.url}/jobs/{job['id']}/steps/{last}", args.token)
    with open("last_step.json", "w") as f:
        json.dump(step, f)
    print(f"wrote last_step.json ({len(step['points']['position'])} material points)")


if __name__ == "__main__":
    main()
