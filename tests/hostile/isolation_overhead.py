#!/usr/bin/env python3
"""Cost of running each job in a child process (docs/service.md "Isolation"): the same N short
jobs (the column example under the half-sine pulse) and M PGA searches of the column through a
1-worker server with `--isolation thread`, then `--isolation process`, alternating rounds;
prints the wall time per job for each. Standard library only.

Usage: isolation_overhead.py BINARY [N_RUNS] [N_SEARCHES] [ROUNDS]
"""
import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hostile  # noqa: E402  (Server, call, load)

N = int(sys.argv[2]) if len(sys.argv) > 2 else 100
M = int(sys.argv[3]) if len(sys.argv) > 3 else 5
ROUNDS = int(sys.argv[4]) if len(sys.argv) > 4 else 2


def batch(s, path, bodies):
    ids = []
    t = time.perf_counter()
    for b in bodies:
        st, _, r = hostile.call(s, "POST", path, b)
        assert st == 202, (st, r)
        ids.append(json.loads(r)["id"])
    for i in ids:
        j = hostile.wait_status(s, f"{path}/{i}", {"succeeded", "failed", "cancelled"}, 600)
        assert j and j["status"] == "succeeded", j
    return (time.perf_counter() - t) / len(ids)


def main():
    column, pulse = hostile.load("column.json"), hostile.load("half-sine-pulse.json")
    free = [b["id"] for b in column["blocks"] if not b.get("fixed")][0]
    search = {"scene": column, "motion": pulse, "criterion": "toppled:" + free,
              "range": {"min": 0, "max": 2, "units": "g"}, "tolerance": 0.05}
    res = {"thread": ([], []), "process": ([], [])}
    for _ in range(ROUNDS):
        for mode in ("thread", "process"):
            s = hostile.Server("--workers", "1", "--isolation", mode)
            res[mode][0].append(batch(s, "/v1/jobs", [{"scene": column, "motion": pulse}] * N))
            if M:
                res[mode][1].append(batch(s, "/v1/pga-searches", [search] * M))
            s.stop()
    for mode, (runs, searches) in res.items():
        line = f"{mode:8s} run: {statistics.median(runs) * 1000:.1f} ms/job (rounds {[round(x * 1000, 1) for x in runs]})"
        if searches:
            line += f"; search: {statistics.median(searches) * 1000:.0f} ms/search ({[round(x * 1000) for x in searches]})"
        print(line, flush=True)


if __name__ == "__main__":
    main()
