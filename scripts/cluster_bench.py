#!/usr/bin/env python3
"""Throughput of the cluster mode (not a test): jobs/s with 1 and 2 `ashlar worker` processes
on one PostgreSQL, against the embedded store with 1 and 2 worker threads; and one PGA search
on the embedded store and on PostgreSQL; and a 2-record fragility search in process vs fanned
out as child jobs over 1 and 2 worker processes (BENCH=fanout: only that). Run through
scripts/cluster_bench.sh, which starts the database. Usage: cluster_bench.py ASHLAR_BINARY DATABASE_URL [JOBS]"""
import json, os, shutil, subprocess, sys, tempfile, time, urllib.request, uuid

BIN, BASE_URL = sys.argv[1], sys.argv[2]
JOBS = int(sys.argv[3]) if len(sys.argv) > 3 else 40


def column(duration):
    return {"format": "ashlar.scene/1", "name": "column on a plinth",
            "materials": {"limestone": {"density": 2500, "young_modulus": 2.0e10, "poisson_ratio": 0.2}},
            "joints": {"dry": {"friction_angle": 40.0}},
            "blocks": [
                {"id": "plinth", "material": "limestone", "fixed": True,
                 "vertices": [[-1.0, -0.5], [1.0, -0.5], [1.0, 0.0], [-1.0, 0.0]]},
                {"id": "column", "material": "limestone",
                 "vertices": [[-0.2, 0.0], [0.2, 0.0], [0.2, 1.2], [-0.2, 1.2]]}],
            "control": {"duration": duration}}


def pulse(a):
    return {"horizontal": {"pulse": {"shape": "sine", "amplitude": a, "period": 0.4, "cycles": 0.5, "units": "m/s2"}}}


def req(addr, method, path, body=None):
    data = json.dumps(body).encode() if body is not None else None
    r = urllib.request.Request(f"http://{addr}{path}", data=data, method=method,
                               headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(r, timeout=60) as resp:
        return json.loads(resp.read())


def fresh_db(tag):
    name = f"bench_{tag}_{uuid.uuid4().hex[:8]}"
    psql = shutil.which("psql") or "/usr/lib/postgresql/15/bin/psql"
    subprocess.run([psql, BASE_URL, "-qc", f"CREATE DATABASE {name}"], check=True)
    return BASE_URL.rsplit("/", 1)[0] + "/" + name


def serve(data, *extra):
    p = subprocess.Popen([BIN, "serve", "--addr", "127.0.0.1:0", "--data", data, *extra],
                         stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    line = p.stdout.readline()
    return p, line.strip().rsplit("http://", 1)[-1]


def worker(url, data, *extra):
    p = subprocess.Popen([BIN, "worker", "--database", url, "--data", data, *extra],
                         stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    p.stdout.readline()
    return p


def stop(*procs):
    for p in procs:
        p.terminate()
    for p in procs:
        p.wait()


def drain(addr, kind_path, ids):
    left = set(ids)
    while left:
        for i in list(left):
            j = req(addr, "GET", f"{kind_path}/{i}")
            if j["status"] in ("succeeded", "failed", "cancelled"):
                assert j["status"] == "succeeded", j
                left.discard(i)
        time.sleep(0.05)


def throughput(addr):
    t0 = time.perf_counter()
    ids = [req(addr, "POST", "/v1/jobs", {"scene": column(10.0), "motion": pulse(2.0 + 0.05 * k)})["id"]
           for k in range(JOBS)]
    drain(addr, "/v1/jobs", ids)
    return JOBS / (time.perf_counter() - t0)


def search(addr):
    body = {"scene": column(4.0), "motion": pulse(2.0), "criterion": "toppled:column",
            "range": {"min": 1.0, "max": 12.0, "units": "m/s2"}, "tolerance": 0.05}
    t0 = time.perf_counter()
    i = req(addr, "POST", "/v1/pga-searches", body)["id"]
    drain(addr, "/v1/pga-searches", [i])
    dt = time.perf_counter() - t0
    return dt, req(addr, "GET", f"/v1/pga-searches/{i}")


def fanout_search(addr, body):
    t0 = time.perf_counter()
    i = req(addr, "POST", "/v1/pga-searches", body)["id"]
    drain(addr, "/v1/pga-searches", [i])
    return time.perf_counter() - t0, req(addr, "GET", f"/v1/pga-searches/{i}")["result"]


def half_sine(period, name):
    return {"name": name, "horizontal": {"pulse": {"amplitude": 1.0, "period": period, "cycles": 0.5, "units": "m/s2"}}}


# A search heavy enough for the fan-out to matter: the full DDA engine (no reduced model), two
# records (a fragility study), 30 s simulated per run.
SEARCH = {"scene": dict(column(30.0), control={"duration": 30.0, "model": "dda"}),
          "motions": [half_sine(0.8, "T = 0.8 s"), half_sine(1.25, "T = 1.25 s")],
          "criterion": "toppled:column", "range": {"min": 1.0, "max": 12.0, "units": "m/s2"},
          "tolerance": 0.05, "scan_points": 6}


def fanout_rows():
    """Wall time of SEARCH: embedded (in-process on the rayon pool), PostgreSQL with the
    search on one worker (--fanout-width 0), and fanned out over 1 and 2 worker processes."""
    rows = []
    s, addr = serve(f"{root}/emb-fan", "--workers", "1")
    rows.append(("embedded (SQLite), in-process search, 1 worker thread", *fanout_search(addr, SEARCH)))
    stop(s)
    configs = [("PostgreSQL, 1 worker process, in-process search (--fanout-width 0)", 1, ["--fanout-width", "0"]),
               ("PostgreSQL, 1 worker process x 1 thread, fanned out", 1, []),
               ("PostgreSQL, 2 worker processes x 1 thread, fanned out", 2, [])]
    for k, (name, n, extra) in enumerate(configs):
        url = fresh_db(f"fan{k}")
        s, addr = serve(f"{root}/api-fan{k}", "--database", url, "--workers", "0")
        ws = [worker(url, f"{root}/wf{k}_{j}", "--workers", "1", *extra) for j in range(n)]
        rows.append((name, *fanout_search(addr, SEARCH)))
        stop(s, *ws)
    ref = rows[0][2]
    runs = sum(len(r["runs"]) for r in ref["records"])
    print(f"\nFragility search (2 records, full DDA column 30 s, toppled:column, 1-12 m/s2, tol 0.05), {runs} runs:")
    for name, t, r in rows:
        print(f"  {name:70s} {t:7.2f} s   same result as embedded: {r == ref}")


root = tempfile.mkdtemp(prefix="ashlar-bench-")
if os.environ.get("BENCH") == "fanout":
    fanout_rows()
    shutil.rmtree(root, ignore_errors=True)
    sys.exit(0)
rows = []
for n in (1, 2):
    s, addr = serve(f"{root}/emb{n}", "--workers", str(n))
    rows.append((f"embedded (SQLite), {n} worker thread(s)", throughput(addr)))
    stop(s)
for n in (1, 2):
    url = fresh_db(f"tp{n}")
    s, addr = serve(f"{root}/api{n}", "--database", url, "--workers", "0")
    ws = [worker(url, f"{root}/w{n}_{k}", "--workers", "1") for k in range(n)]
    rows.append((f"PostgreSQL, API + {n} worker process(es) x 1 thread", throughput(addr)))
    stop(s, *ws)
print(f"\n{JOBS} jobs (column, 10 s simulated, half-sine pulse), submitted at once:")
for name, r in rows:
    print(f"  {name:55s} {r:6.2f} jobs/s")

s, addr = serve(f"{root}/emb-search", "--workers", "1")
t_emb, r_emb = search(addr)
stop(s)
url = fresh_db("search")
s, addr = serve(f"{root}/api-search", "--database", url, "--workers", "0")
w = worker(url, f"{root}/w-search", "--workers", "1")
t_pg, r_pg = search(addr)
stop(s, w)
same = r_emb["result"]["safe_pga"] == r_pg["result"]["safe_pga"] and r_emb["result"]["failing_pga"] == r_pg["result"]["failing_pga"]
print(f"\nPGA search (column 4 s, toppled:column, 1-12 m/s2, tolerance 0.05), {len(r_emb['result']['runs'])} runs:")
print(f"  embedded store          {t_emb:6.2f} s")
print(f"  PostgreSQL + 1 worker   {t_pg:6.2f} s   (same bracket: {same})")
fanout_rows()
shutil.rmtree(root, ignore_errors=True)
