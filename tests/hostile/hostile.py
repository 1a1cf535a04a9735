#!/usr/bin/env python3
"""Hostile-client suite (docs/service.md): replays each attack listed in docs/service.md against the real
`ashlar serve` binary on loopback and asserts the refusal, that the server stays up, and that
its peak memory (VmHWM) stays under a bound. Samples /healthz through the whole suite and
prints its latency. Standard library only.

Usage: hostile.py BINARY   (run by tests/hostile/run.sh)
"""
import hashlib
import hmac
import json
import os
import resource
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BIN = sys.argv[1]
RSS_BOUND_MB = 300
FAILURES = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        FAILURES.append(what)


class Server:
    def __init__(self, *args, runner="real", env=None, data=None, nofile=None):
        self.dir = tempfile.mkdtemp(prefix="ashlar-hostile-")
        self.data_dir = data or os.path.join(self.dir, "data")
        cmd = [BIN, "serve", "--addr", "127.0.0.1:0", "--data", self.data_dir, *args]
        if runner == "fake":
            cmd.append("--fake-runner")
        self.out = open(os.path.join(self.dir, "stdout"), "w+")
        self.err = open(os.path.join(self.dir, "stderr"), "w+")
        def limit_fds():
            # The machine: 1024 file descriptors for the server.
            if nofile:
                resource.setrlimit(resource.RLIMIT_NOFILE, (nofile, resource.getrlimit(resource.RLIMIT_NOFILE)[1]))

        self.proc = subprocess.Popen(cmd, stdout=self.out, stderr=self.err, env=dict(os.environ, **(env or {})),
                                     preexec_fn=limit_fds)
        self.addr = None
        for _ in range(400):
            self.out.seek(0)
            for line in self.out.read().splitlines():
                if line.startswith("ashlar serve: listening on "):
                    self.addr = line.split("listening on ")[1].strip()
            if self.addr:
                break
            if self.proc.poll() is not None:
                self.err.seek(0)
                raise SystemExit("server did not start: " + self.err.read())
            time.sleep(0.05)
        hostport = self.addr.split("//")[1]
        self.host, self.port = hostport.split(":")[0], int(hostport.split(":")[1])

    def data(self):
        return self.data_dir

    def children(self):
        """Pids of the server's child processes (the jobs' `internal-run-job` processes)."""
        pids = []
        for task in os.listdir(f"/proc/{self.proc.pid}/task"):
            with open(f"/proc/{self.proc.pid}/task/{task}/children") as f:
                pids += [int(x) for x in f.read().split()]
        return pids

    def alive(self):
        return self.proc.poll() is None

    def hwm_mb(self):
        with open(f"/proc/{self.proc.pid}/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
        return -1

    def fds(self):
        return len(os.listdir(f"/proc/{self.proc.pid}/fd"))

    def stop(self):
        self.proc.terminate()
        try:
            self.proc.wait(30)
        except subprocess.TimeoutExpired:
            self.proc.kill()


def call(s, method, path, body=None, raw=None, headers=None, timeout=60):
    data = raw if raw is not None else (None if body is None else json.dumps(body).encode())
    h = {"content-type": "application/json"}
    h.update(headers or {})
    req = urllib.request.Request(s.addr + path, data=data, method=method, headers=h)
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, r.headers, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.headers, e.read()


def streamed_bytes(url, timeout=120):
    """GET `url` and count its body's bytes, read 1 MiB at a time (never held whole)."""
    total = 0
    with urllib.request.urlopen(urllib.request.Request(url), timeout=timeout) as r:
        while True:
            c = r.read(1 << 20)
            if not c:
                return total
            total += len(c)


def raw_request(s, head, body=b"", timeout=30):
    """Send raw bytes, tolerate the server closing early, return (status, headers, body)."""
    sock = socket.create_connection((s.host, s.port), timeout=timeout)
    try:
        sock.sendall(head)
        for i in range(0, len(body), 1 << 16):
            sock.sendall(body[i:i + (1 << 16)])
    except (BrokenPipeError, ConnectionResetError):
        pass
    data = b""
    try:
        while True:
            chunk = sock.recv(1 << 16)
            if not chunk:
                break
            data += chunk
            if b"\r\n\r\n" in data:
                hdr, _, rest = data.partition(b"\r\n\r\n")
                cl = [l for l in hdr.split(b"\r\n") if l.lower().startswith(b"content-length:")]
                if cl and len(rest) >= int(cl[0].split(b":")[1]):
                    break
    except (ConnectionResetError, socket.timeout):
        pass
    sock.close()
    if not data:
        return None, {}, b""
    hdr, _, rest = data.partition(b"\r\n\r\n")
    lines = hdr.decode("latin-1").split("\r\n")
    status = int(lines[0].split()[1])
    headers = {l.split(":", 1)[0].lower(): l.split(":", 1)[1].strip() for l in lines[1:] if ":" in l}
    return status, headers, rest


def problem(status, headers, body):
    ct = headers.get("content-type") if isinstance(headers, dict) else headers.get("content-type")
    try:
        return (ct or "").startswith("application/problem+json"), json.loads(body)
    except ValueError:
        return False, {}


class Healthz(threading.Thread):
    """Samples GET /healthz every 50 ms on a fresh connection."""

    def __init__(self, s):
        super().__init__(daemon=True)
        self.s, self.samples, self.errors, self.paused, self.done = s, [], [], False, False

    def run(self):
        while not self.done:
            if not self.paused:
                t = time.perf_counter()
                try:
                    status, _, _ = call(self.s, "GET", "/healthz", timeout=10)
                    dt = (time.perf_counter() - t) * 1000
                    if status == 200:
                        self.samples.append(dt)
                    else:
                        self.errors.append(f"status {status}")
                except Exception as e:  # noqa: BLE001 - any failure is a sample lost
                    self.errors.append(repr(e))
            time.sleep(0.05)

    def report(self):
        xs = sorted(self.samples)
        if not xs:
            return "no samples"
        q = lambda p: xs[min(len(xs) - 1, int(p * len(xs)))]
        return f"{len(xs)} samples, p50 {q(0.5):.2f} ms, p99 {q(0.99):.2f} ms, max {xs[-1]:.2f} ms, {len(self.errors)} failed"


def load(name):
    with open(os.path.join(ROOT, "examples", name)) as f:
        return json.load(f)


def big_scene(base, n_blocks, control):
    mat = list(base["materials"])[0]
    blocks = [{"id": "base", "material": mat, "fixed": True,
               "vertices": [[-1e4, -1], [1e4, -1], [1e4, 0], [-1e4, 0]]}]
    for i in range(n_blocks - 1):
        x = i * 0.5 - 1e4
        blocks.append({"id": f"b{i}", "material": mat,
                       "vertices": [[x, 0], [x + 0.4, 0], [x + 0.4, 0.4], [x, 0.4]]})
    s = json.loads(json.dumps(base))
    s["blocks"] = blocks
    s["control"] = control
    return s


def wait_status(s, path, want, timeout=120):
    end = time.time() + timeout
    while time.time() < end:
        st, _, b = call(s, "GET", path)
        if st == 200 and json.loads(b)["status"] in want:
            return json.loads(b)
        time.sleep(0.2)
    return None


def pid_alive(pid):
    """A process that exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def isolation():
    """6. Jobs run in child processes with limits: a job that exhausts its memory or crashes
    fails alone (the cause named) while a job on the other worker succeeds, the server's memory
    stays flat; a SIGKILLed server leaves no child running and its job is run again."""
    column, pulse = load("column.json"), load("half-sine-pulse.json")
    faults = {"ASHLAR_TEST_FAULTS": "1"}  # honoured by debug builds only (src/service/worker/runner.rs)
    i = Server("--workers", "2", "--job-memory-limit", "256M", env=faults)
    rss0 = i.hwm_mb()
    good_scene = json.loads(json.dumps(column))
    good_scene["control"] = dict(good_scene.get("control") or {}, duration=30)
    st, _, b = call(i, "POST", "/v1/jobs", {"scene": good_scene, "motion": pulse})
    good = json.loads(b)["id"]
    bad = {}
    for name in ["fault:alloc", "fault:segv", "fault:alloc", "fault:abort"]:
        st, _, b = call(i, "POST", "/v1/jobs", {"scene": dict(column, name=name), "motion": pulse})
        bad.setdefault(name, []).append(json.loads(b)["id"])
    for name, want in [("fault:alloc", "job memory limit of 268435456 bytes"), ("fault:segv", "signal 11"),
                       ("fault:abort", "signal 6")]:
        for jid in bad[name]:
            j = wait_status(i, f"/v1/jobs/{jid}", {"failed", "succeeded", "cancelled"}, 120)
            err = (j or {}).get("error") or ""
            check(j is not None and j["status"] == "failed" and want in err,
                  f"a {name} job fails alone with its cause ({j and j['status']}: {err[:110]})")
    j = wait_status(i, f"/v1/jobs/{good}", {"failed", "succeeded", "cancelled"}, 300)
    check(j is not None and j["status"] == "succeeded",
          f"the job beside them on the other worker succeeds ({j and j['status']}: {j and j.get('error')})")
    rss1 = i.hwm_mb()
    check(i.alive() and rss1 - rss0 < 30,
          f"the server stays up, peak RSS {rss0:.0f} → {rss1:.0f} MB through 4 failed jobs (two of 256 MB)")
    # A SIGKILLed server: its job's process dies with it; the next server runs the job again.
    blocker = json.loads(json.dumps(column))
    blocker["control"] = dict(blocker.get("control") or {}, duration=2000)
    st, _, b = call(i, "POST", "/v1/jobs", {"scene": blocker, "motion": pulse})
    jid = json.loads(b)["id"]
    wait_status(i, f"/v1/jobs/{jid}", {"running"}, 60)
    # "running" is recorded before the job's process is spawned: wait for the process to appear
    # (CI once read the children in between and saw none).
    kids, deadline = [], time.time() + 30
    while not kids and time.time() < deadline:
        kids = i.children()
        if not kids:
            time.sleep(0.05)
    i.proc.kill()
    i.proc.wait(10)
    time.sleep(1.0)
    left = [p for p in kids if pid_alive(p)]
    check(kids and not left, f"SIGKILL of the server: its job processes {kids} end with it (left: {left})")
    r = Server("--workers", "1", data=i.data_dir, env=faults)
    j = wait_status(r, f"/v1/jobs/{jid}", {"running"}, 60)
    check(j is not None and j["attempts"] == 2, f"the restarted server runs the job again (attempt {j and j['attempts']})")
    call(r, "POST", f"/v1/jobs/{jid}/cancel", {})
    j = wait_status(r, f"/v1/jobs/{jid}", {"cancelled", "failed", "succeeded"}, 60)
    check(j is not None and j["status"] == "cancelled", f"and cancels it in its process ({j and j['status']})")
    r.stop()


def main():
    t0 = time.time()
    column, pulse = load("column.json"), load("half-sine-pulse.json")
    mat = list(column["materials"])[0]

    # --- A non-loopback address without access control is refused.
    r = subprocess.run([BIN, "serve", "--addr", "0.0.0.0:0", "--data", tempfile.mkdtemp()],
                       capture_output=True, text=True, timeout=30)
    check(r.returncode != 0 and "--allow-insecure" in r.stderr,
          "serve --addr 0.0.0.0 without --allow-insecure is refused")

    # --- 3. Access: with --tokens, /v1/ needs a bearer token (401 problem+json without one).
    tokfile = os.path.join(tempfile.mkdtemp(), "tokens")
    with open(tokfile, "w") as f:
        f.write("# role token\nadmin hostile-suite-admin-token\n"
                "user hostile-suite-user-token-a\nuser hostile-suite-user-token-b\n")
    keyfile = os.path.join(os.path.dirname(tokfile), "signing.key")
    signing_key = b"hostile-suite-signing-key-0123456789abcdef"
    with open(keyfile, "wb") as f:
        f.write(signing_key)
    t = Server("--workers", "1", "--tokens", tokfile, "--signing-key-file", keyfile,
               "--max-queued-jobs-per-token", "3", runner="fake")
    st, h, b = call(t, "GET", "/v1/jobs?limit=500")
    check(st == 401 and problem(st, h, b)[0] and (h.get("www-authenticate") or "").startswith("Bearer"),
          f"GET /v1/jobs without a token: 401 problem+json with WWW-Authenticate ({st})")
    st, _, _ = call(t, "POST", "/v1/jobs", {"scene": column, "motion": pulse},
                    headers={"Authorization": "Bearer not-the-right-token-at-all"})
    check(st == 401, f"POST /v1/jobs with a wrong token: 401 ({st})")
    st, _, _ = call(t, "POST", "/v1/jobs", {"scene": column, "motion": pulse},
                    headers={"Authorization": "Bearer hostile-suite-admin-token"})
    check(st == 202, f"POST /v1/jobs with a token of the file: 202 ({st})")
    st, _, _ = call(t, "GET", "/healthz")
    check(st == 200, f"/healthz stays open: {st}")

    # Ownership: a user sees only its own jobs (others' answer 404, not 403); an admin all.
    A = {"Authorization": "Bearer hostile-suite-user-token-a"}
    B = {"Authorization": "Bearer hostile-suite-user-token-b"}
    ADMIN = {"Authorization": "Bearer hostile-suite-admin-token"}
    st, _, b = call(t, "POST", "/v1/jobs", {"scene": column, "motion": pulse}, headers=A)
    a_job = json.loads(b)["id"] if st == 202 else "none"
    st, _, b = call(t, "POST", "/v1/jobs", {"scene": column, "motion": pulse}, headers=ADMIN)
    admin_job = json.loads(b)["id"] if st == 202 else "none"
    codes = [call(t, m, f"/v1/jobs/{a_job}{tail}", headers=B)[0]
             for m, tail in [("GET", ""), ("GET", "/trajectory.mcap"), ("POST", "/cancel"), ("DELETE", "")]]
    check(codes == [404] * 4, f"another user's job: GET, trajectory, cancel, DELETE all 404 ({codes})")
    st, _, b = call(t, "GET", "/v1/jobs?limit=500", headers=B)
    check(st == 200 and json.loads(b)["jobs"] == [], f"another user's jobs are not listed ({st})")
    def wait_status_h(path, want, h, timeout=60):
        end = time.time() + timeout
        while time.time() < end:
            st, _, b = call(t, "GET", path, headers=h)
            if st == 200 and json.loads(b)["status"] in want:
                return json.loads(b)
            time.sleep(0.1)
        return None

    done_admin = wait_status_h(f"/v1/jobs/{admin_job}", {"succeeded", "failed"}, ADMIN)
    st, _, _ = call(t, "DELETE", f"/v1/jobs/{admin_job}", headers=A)
    st2, _, _ = call(t, "GET", f"/v1/jobs/{admin_job}", headers=ADMIN)
    check(done_admin is not None and st == 404 and st2 == 200,
          f"a user cannot delete an admin's job: DELETE {st}, the admin still reads it ({st2})")
    st, _, b = call(t, "GET", "/v1/jobs?limit=500", headers=ADMIN)
    ids = [j["id"] for j in json.loads(b)["jobs"]] if st == 200 else []
    check(a_job in ids and admin_job in ids, "the admin lists every token's jobs")

    # Signed links: a's finished job gives signed URLs that open without a header; tampered or
    # expired ones are 401 problem+json.
    done_a = wait_status_h(f"/v1/jobs/{a_job}", {"succeeded", "failed"}, A)
    signed = (done_a or {}).get("signed_links") or {}
    traj = signed.get("trajectory", "")
    st, _, body = call(t, "GET", traj) if traj else (None, None, b"")
    check(st == 200 and len(body) > 0, f"a signed trajectory link opens without a header ({st}, {len(body)} bytes)")
    if traj:
        path, query = traj.split("?", 1)
        q = dict(kv.split("=", 1) for kv in query.split("&"))
        flipped = ("1" if q["sig"][0] == "0" else "0") + q["sig"][1:]
        st, h, b = call(t, "GET", f"{path}?expires={q['expires']}&sig={flipped}")
        check(st == 401 and problem(st, h, b)[0], f"a tampered signed link: 401 problem+json ({st})")
        st, h, b = call(t, "GET", f"{path}?expires={int(q['expires']) + 86400}&sig={q['sig']}")
        check(st == 401, f"a signed link with a later expiry: 401 ({st})")
        old = int(time.time()) - 60
        sig = hmac.new(signing_key, f"GET\n{path}\n{old}".encode(), hashlib.sha256).hexdigest()
        st, h, b = call(t, "GET", f"{path}?expires={old}&sig={sig}")
        ok, p = problem(st, h, b)
        check(st == 401 and ok and "expired" in p.get("detail", ""),
              f"an expired signed link (right signature): 401 saying expired ({st}: {p.get('detail')})")
        st, _, _ = call(t, "GET", f"/v1/jobs/{a_job}?expires={q['expires']}&sig={q['sig']}")
        check(st == 401, f"a signed link is not accepted on another route ({st})")

    # Per-token quota: b fills its 3 queued jobs (the worker busy with a long one), gets 429
    # naming the quota and the count; a is not affected.
    slow = json.loads(json.dumps(column))
    slow["control"] = dict(slow.get("control") or {}, duration=600)
    codes = []
    last = None
    for _ in range(8):
        st, h, b = call(t, "POST", "/v1/jobs", {"scene": slow, "motion": pulse}, headers=B)
        codes.append(st)
        if st == 429:
            last = (st, h, b)
            break
    ok, p = problem(*last) if last else (False, {})
    check(ok and "--max-queued-jobs-per-token" in p.get("detail", "") and "3 waiting, limit 3" in p.get("detail", ""),
          f"per-token quota: 429 naming the quota and the count after {codes.count(202)} accepted ({p.get('detail')})")
    st, _, _ = call(t, "POST", "/v1/jobs", {"scene": column, "motion": pulse}, headers=A)
    check(st == 202, f"another token's quota is its own: 202 ({st})")
    t.stop()
    p = subprocess.Popen([BIN, "serve", "--addr", "0.0.0.0:0", "--tokens", tokfile, "--data", tempfile.mkdtemp()],
                         stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    line = p.stdout.readline()
    p.terminate()
    p.wait(30)
    check(line.startswith("ashlar serve: listening on"), "serve --addr 0.0.0.0 with --tokens starts")
    origin_check = Server("--workers", "1", runner="fake")
    req = urllib.request.Request(origin_check.addr + "/v1/jobs", method="OPTIONS",
                                 headers={"Origin": "https://evil.example", "Access-Control-Request-Method": "POST"})
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            allow = r.headers.get("access-control-allow-origin")
    except urllib.error.HTTPError as e:
        allow = e.headers.get("access-control-allow-origin")
    check(allow is None, f"a preflight from https://evil.example is not allowed ({allow})")
    origin_check.stop()

    # The suite opens 1100 connections at once (the flood): its own descriptor limit
    # must allow them; the server keeps the 1024.
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft < 4096 and (hard == resource.RLIM_INFINITY or hard >= 4096):
        resource.setrlimit(resource.RLIMIT_NOFILE, (4096, hard))
    s = Server("--workers", "1", "--max-queued-jobs", "20", "--max-job-seconds", "5",
               "--header-timeout", "2", "--body-timeout", "2", "--max-connections", "200", nofile=1024)
    hz = Healthz(s)
    hz.start()

    # --- 1. Budgets: the probes of the issue are refused with 422 naming the limit.
    probe = big_scene(column, 5000, {"duration": 2000, "time_step": 1e-3, "output_interval": 1e-3})
    st, h, b = call(s, "POST", "/v1/jobs", {"scene": probe, "motion": pulse})
    ok, p = problem(st, h, b)
    check(st == 422 and ok and "block-steps" in p.get("detail", ""),
          f"5000 blocks × 2000 s at 1 ms: 422 over the work budget ({st}: {p.get('detail', '')[:120]})")
    long_scene = json.loads(json.dumps(column))
    long_scene["control"] = {"duration": 2000, "time_step": 1e-3}
    search = {"scene": long_scene, "motions": [dict(pulse, name=f"r{i}") for i in range(100)],
              "criterion": "toppled:" + [b["id"] for b in column["blocks"] if not b.get("fixed")][0],
              "range": {"min": 0, "max": 1, "units": "g"}, "scan_points": 64}
    st, h, b = call(s, "POST", "/v1/pga-searches", search)
    ok, p = problem(st, h, b)
    check(st == 422 and ok and "max-search-block-steps" in p.get("detail", ""),
          f"search of 100 records × 64 scan points × 2e6 steps: 422 ({st}: {p.get('detail', '')[:120]})")

    # --- 7. Impossible physical values: 422 with the pointer, short message.
    cases = [
        (("materials", mat, "density"), f"/scene/materials/{mat}/density"),
        (("materials", mat, "young_modulus"), f"/scene/materials/{mat}/young_modulus"),
        (("gravity",), "/scene/gravity"),
        (("control", "penalty_stiffness"), "/scene/control/penalty_stiffness"),
        (("control", "duration"), "/scene/control/duration"),
    ]
    for path, pointer in cases:
        sc = json.loads(json.dumps(column))
        node = sc
        for k in path[:-1]:
            node = node.setdefault(k, {})
        node[path[-1]] = 1e308
        st, h, b = call(s, "POST", "/v1/jobs", {"scene": sc, "motion": pulse})
        ok, p = problem(st, h, b)
        check(st == 422 and p.get("pointer") == pointer and len(p.get("detail", "")) < 300,
              f"{pointer} = 1e308: 422 at its pointer ({st} {p.get('pointer')}: {p.get('detail', '')[:100]})")
    sc = json.loads(json.dumps(column))
    free = [b["id"] for b in sc["blocks"] if not b.get("fixed")][0]
    sc["initial"] = [{"block": free, "velocity": [1e308, 0]}]
    st, h, b = call(s, "POST", "/v1/jobs", {"scene": sc, "motion": pulse})
    ok, p = problem(st, h, b)
    check(st == 422 and p.get("pointer") == "/scene/initial/0/velocity/0",
          f"initial velocity 1e308: 422 at /scene/initial/0/velocity/0 ({st} {p.get('pointer')})")

    # --- 2. A 16 MB body of ~190 k blocks: refused while reading, eight at once.
    mem_before = s.hwm_mb()
    blocks = [{"id": f"b{i}", "material": mat, "vertices": [[0, 0], [1, 0], [1, 1]]} for i in range(190_000)]
    body = json.dumps({"scene": dict(column, blocks=blocks), "motion": pulse}).encode()
    body = body[: 16 * 1024 * 1024 - 10] if len(body) > 16 * 1024 * 1024 else body
    results = []

    def big_post():
        head = (f"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                f"Content-Length: {len(body)}\r\nConnection: close\r\n\r\n").encode()
        results.append(raw_request(s, head, body))

    threads = [threading.Thread(target=big_post) for _ in range(8)]
    t = time.perf_counter()
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    dt = time.perf_counter() - t
    statuses = sorted(r[0] for r in results)
    check(all(r[0] == 422 and json.loads(r[2]).get("pointer") == "/scene/blocks" for r in results),
          f"8 × {len(body) >> 20} MB bodies of {len(blocks)} blocks: 422 at /scene/blocks in {dt:.1f} s ({statuses})")
    print(f"info peak RSS before {mem_before:.0f} MB, after the 8 big bodies {s.hwm_mb():.0f} MB", flush=True)

    # Over --max-body-bytes: 413 problem+json, at once from Content-Length.
    head = (b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
            b"Content-Length: 20000000\r\nConnection: close\r\n\r\n")
    st, h, b = raw_request(s, head, b"{" * 100000)
    check(st == 413 and h.get("content-type", "").startswith("application/problem+json"),
          f"a 20 MB Content-Length: 413 problem+json ({st})")
    # Chunked, no length: refused while reading once past the limit.
    chunk = b"0" * 1_000_000
    chunked = b"".join(b"%x\r\n" % len(chunk) + chunk + b"\r\n" for _ in range(18)) + b"0\r\n\r\n"
    head = (b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
            b"Transfer-Encoding: chunked\r\nConnection: close\r\n\r\n")
    st, h, b = raw_request(s, head, chunked)
    check(st == 413, f"an 18 MB chunked body: 413 while reading ({st})")
    # Too many JSON values in a small body.
    st, h, b = call(s, "POST", "/v1/jobs", raw=b"[" + b"0," * 2_100_000 + b"0]")
    ok, p = problem(st, h, b)
    check(st == 422 and ok and "max-json-values" in p.get("detail", ""),
          f"2.1 M JSON values: 422 while reading ({st})")

    # --- 8. Small: 405 names the methods; 431 is problem+json.
    st, h, b = call(s, "PUT", "/v1/jobs")
    ok, p = problem(st, h, b)
    check(st == 405 and "POST" in p.get("detail", "") and "GET" in p.get("detail", ""),
          f"PUT /v1/jobs: 405 naming the methods ({p.get('detail')})")
    st, h, b = raw_request(s, b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Big: " + b"a" * 40000 + b"\r\nConnection: close\r\n\r\n")
    check(st == 431 and h.get("content-type", "").startswith("application/problem+json"),
          f"40 KB of headers: 431 problem+json ({st})")
    st, h, b = raw_request(s, b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Big: " + b"a" * 300_000 + b"\r\nConnection: close\r\n\r\n")
    ok, p = problem(st, h, b)
    check(st == 431 and ok and p.get("status") == 431,
          f"300 KB of headers (beyond hyper's buffer): 431 problem+json ({st} {h.get('content-type')})")

    # --- 5. Queue limit atomic: the worker busy with a blocker, 60 concurrent POSTs, limit 20.
    # A 56-block wall on the full engine for 1e6 steps (5.6e7 block-steps, inside every budget):
    # minutes of work, so the 5 s wall-clock limit is what ends it. A single block no longer
    # serves: its 2e6 steps (the step limit) finish in under 5 s.
    blocker = load("wall-window.json")
    blocker["control"] = dict(blocker.get("control") or {}, duration=1000, time_step=1e-3,
                              model="dda", output_interval=10)
    st, _, b = call(s, "POST", "/v1/jobs", {"scene": blocker, "motion": None})
    blocker_id = json.loads(b)["id"] if st == 202 else None
    check(st == 202 and wait_status(s, f"/v1/jobs/{blocker_id}", {"running"}, 30) is not None,
          "a long job occupies the only worker")
    codes = []
    lock = threading.Lock()

    def submit():
        st, _, _ = call(s, "POST", "/v1/jobs", {"scene": column, "motion": pulse})
        with lock:
            codes.append(st)

    threads = [threading.Thread(target=submit) for _ in range(60)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    check(codes.count(202) == 20 and codes.count(429) == 40,
          f"60 concurrent POSTs with --max-queued-jobs 20: {codes.count(202)} × 202, {codes.count(429)} × 429")

    # --- 1. Wall-clock limit: the blocker is stopped and failed after --max-job-seconds 5.
    j = wait_status(s, f"/v1/jobs/{blocker_id}", {"failed", "succeeded", "cancelled"}, 60)
    check(j is not None and j["status"] == "failed" and "max-job-seconds" in (j.get("error") or ""),
          f"a job over --max-job-seconds fails with the limit named ({j and j['status']}: {j and j.get('error')})")

    # --- DELETE: a finished job goes (204, then 404); a queued one is refused (409).
    st, _, _ = call(s, "DELETE", f"/v1/jobs/{blocker_id}")
    st2, _, _ = call(s, "GET", f"/v1/jobs/{blocker_id}")
    check(st == 204 and st2 == 404 and not os.path.exists(os.path.join(s.data(), "jobs", blocker_id)),
          f"DELETE a finished job: {st}, then GET {st2}, artifacts removed")
    st, _, b = call(s, "GET", "/v1/jobs?limit=5")
    queued = [x["id"] for x in json.loads(b)["jobs"] if x["status"] == "queued"] if st == 200 else []
    if queued:
        st, _, _ = call(s, "DELETE", f"/v1/jobs/{queued[0]}")
        check(st == 409, f"DELETE a queued job: 409 ({st})")

    # --- 2. Streaming: a 300 MB trajectory and a 200 MB history, read by ranges and whole.
    done = wait_status(s, f"/v1/jobs/{queued[-1]}" if queued else "/v1/jobs/none", {"succeeded"}, 300)
    if done:
        jid = done["id"]
        jdir = os.path.join(s.data(), "jobs", jid)
        # Written into the job's directory by the test: recording one takes many minutes.
        with open(os.path.join(jdir, "trajectory.mcap"), "r+b") as f:
            f.truncate(300 << 20)
        with open(os.path.join(jdir, "histories.csv")) as f:
            lines = f.read().splitlines()
        with open(os.path.join(jdir, "histories.csv"), "w") as f:
            f.write(lines[0] + "\n")
            row = lines[1] + "\n"
            block = row * 10000
            n = 0
            while n < (200 << 20):
                f.write(block)
                n += len(block)
        res = []

        def ranged():
            res.append(call(s, "GET", f"/v1/jobs/{jid}/trajectory.mcap", headers={"Range": "bytes=0-99"}))

        threads = [threading.Thread(target=ranged) for _ in range(8)]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        check(all(r[0] == 206 and len(r[2]) == 100 for r in res),
              "8 concurrent Range: bytes=0-99 of a 300 MB trajectory: 206, 100 bytes each")
        total = streamed_bytes(f"{s.addr}/v1/jobs/{jid}/trajectory.mcap")
        check(total == 300 << 20, f"the whole 300 MB trajectory streamed ({total >> 20} MB)")
        total = streamed_bytes(f"{s.addr}/v1/jobs/{jid}/histories?format=csv")
        check(total >= 200 << 20, f"a 200 MB history streamed as CSV ({total >> 20} MB)")
        st, h, b = call(s, "GET", f"/v1/jobs/{jid}/histories")
        check(st == 406, f"the same history as JSON: 406 pointing to CSV or ?every ({st})")
        st, h, b = call(s, "GET", f"/v1/jobs/{jid}/histories?every=1000")
        check(st == 200 and len(json.loads(b)["time"]) > 100, f"as JSON with ?every=1000: 200 ({st})")
        # Eight clients ask at once for a 7.9 MB (7.5 MiB) history as JSON (under the 8 MiB JSON ceiling):
        # each answer is written from the numbers as it is sent, and at most two are built at
        # once (before: 4.7 GB peak, each request holding text, numbers and a JSON tree).
        other = wait_status(s, f"/v1/jobs/{queued[-2]}", {"succeeded"}, 300) if len(queued) > 1 else None
        if other:
            p31 = os.path.join(s.data(), "jobs", other["id"], "histories.csv")
            with open(p31) as f:
                lines = f.read().splitlines()
            with open(p31, "w") as f:
                f.write(lines[0] + "\n")
                block = (lines[1] + "\n") * 10000
                n = 0
                while n < (60 << 17):
                    f.write(block)
                    n += len(block)
            rows = n // len(lines[1] + "\n")
            res = []
            th = [threading.Thread(target=lambda: res.append(
                call(s, "GET", f"/v1/jobs/{other['id']}/histories", timeout=300))) for _ in range(8)]
            t = time.perf_counter()
            for x in th:
                x.start()
            for x in th:
                x.join()
            ok = all(r[0] == 200 and len(json.loads(r[2])["time"]) == rows for r in res)
            check(ok and len({r[2] for r in res}) == 1,
                  f"8 concurrent JSON histories of a 7.9 MB CSV: 200, {rows} frames each, in "
                  f"{time.perf_counter() - t:.1f} s; peak RSS now {s.hwm_mb():.0f} MB")
        else:
            check(False, "a second job to read histories from succeeded")
        print(f"info peak RSS after streaming: {s.hwm_mb():.0f} MB", flush=True)
    else:
        check(False, "a job to stream artifacts from succeeded")

    # --- 4. Slow clients: half-sent headers and bodies are cut; the connection limit holds.
    st, h, b = raw_request(s, b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 1000\r\n\r\n{", timeout=20)
    check(st == 408, f"a body that stops arriving: 408 after --body-timeout ({st})")
    hz.paused = True
    socks = []
    cut = 0  # connections the server closed at once (over --max-connections)
    for _ in range(1100):
        try:
            c = socket.create_connection((s.host, s.port), timeout=5)
            socks.append(c)
            c.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Slow: ")
        except OSError:
            cut += 1
    time.sleep(0.5)
    fds = s.fds()
    check(len(socks) == 1100 and fds < 200 + 60,
          f"{len(socks)} half-sent requests ({cut} cut at once; server limited to 1024 descriptors): "
          f"it holds {fds} descriptors (limit 200 connections)")
    t = time.time()
    ok = False
    while time.time() - t < 15:
        try:
            st, _, _ = call(s, "GET", "/healthz", timeout=2)
            if st == 200:
                ok = True
                break
        except Exception:  # noqa: BLE001
            time.sleep(0.2)
    check(ok, f"/healthz answers again {time.time() - t:.1f} s into the flood (header timeout 2 s)")
    for c in socks:
        c.close()
    hz.paused = False

    # --- Disk quota and per-job artifact limit (a second server, fake runner).
    q = Server("--workers", "1", "--max-artifact-bytes", "1", runner="fake")
    st, _, b = call(q, "POST", "/v1/jobs", {"scene": column, "motion": pulse})
    first = json.loads(b)["id"]
    wait_status(q, f"/v1/jobs/{first}", {"succeeded"}, 30)
    time.sleep(0.2)
    st, h, b = call(q, "POST", "/v1/jobs", {"scene": column, "motion": pulse})
    check(st == 507 and problem(st, h, b)[0], f"over --max-artifact-bytes: 507 problem+json ({st})")
    call(q, "DELETE", f"/v1/jobs/{first}")
    st, _, _ = call(q, "POST", "/v1/jobs", {"scene": column, "motion": pulse})
    check(st == 202, f"after DELETE of the finished job: accepted again ({st})")
    q.stop()
    a = Server("--workers", "1", "--max-job-artifact-bytes", "20000")
    sc = json.loads(json.dumps(column))
    sc["control"] = dict(sc.get("control", {}), duration=300, output_interval=0.001)
    st, _, b = call(a, "POST", "/v1/jobs", {"scene": sc, "motion": None})
    j = wait_status(a, f"/v1/jobs/{json.loads(b)['id']}", {"failed", "succeeded"}, 120) if st == 202 else None
    check(j is not None and j["status"] == "failed" and "max-job-artifact-bytes" in (j.get("error") or ""),
          f"a job writing over --max-job-artifact-bytes fails with the limit named ({j and j.get('error')})")
    a.stop()

    # --- 2. Shared artifact storage (--artifacts, as API processes of a cluster): a trajectory
    # this process has not cached is downloaded to disk in chunks, once for concurrent readers
    # (before: each request held the whole file in memory, 3.3 GB for these eight).
    shared = tempfile.mkdtemp(prefix="ashlar-hostile-shared-")
    c = Server("--workers", "1", "--artifacts", "file://" + shared, runner="fake")
    st, _, b = call(c, "POST", "/v1/jobs", {"scene": column, "motion": pulse})
    jid = json.loads(b)["id"] if st == 202 else "none"
    if wait_status(c, f"/v1/jobs/{jid}", {"succeeded"}, 60):
        import shutil
        shutil.rmtree(os.path.join(c.data(), "jobs", jid), ignore_errors=True)  # not cached here
        with open(os.path.join(shared, "jobs", jid, "trajectory.mcap"), "r+b") as f:
            f.truncate(300 << 20)
        rss0 = c.hwm_mb()
        res = []
        th = [threading.Thread(target=lambda: res.append(call(
            c, "GET", f"/v1/jobs/{jid}/trajectory.mcap", headers={"Range": "bytes=0-99"}, timeout=300)))
            for _ in range(8)]
        for x in th:
            x.start()
        for x in th:
            x.join()
        hwm = c.hwm_mb()
        check(all(r[0] == 206 and len(r[2]) == 100 for r in res) and hwm < RSS_BOUND_MB,
              f"8 concurrent ranges of a 300 MB trajectory in shared storage, not cached: 206 × "
              f"{sum(r[0] == 206 for r in res)}, peak RSS {rss0:.0f} → {hwm:.0f} MB (bound {RSS_BOUND_MB} MB)")
    else:
        check(False, "a job publishing to shared storage succeeded")
    c.stop()

    isolation()

    hz.done = True
    hz.join()
    alive = s.alive()
    hwm = s.hwm_mb()
    check(alive, "the server is still up after every attack")
    check(hwm < RSS_BOUND_MB, f"peak RSS of the server through the suite: {hwm:.0f} MB (bound {RSS_BOUND_MB} MB)")
    print(f"info /healthz during the suite (outside the connection flood): {hz.report()}", flush=True)
    check(not hz.errors, f"/healthz never failed outside the flood ({hz.errors[:3]})")
    s.stop()
    print(f"info suite took {time.time() - t0:.0f} s", flush=True)
    if FAILURES:
        print(f"hostile: {len(FAILURES)} FAILED", file=sys.stderr)
        sys.exit(1)
    print("hostile: all passed")


if __name__ == "__main__":
    main()
