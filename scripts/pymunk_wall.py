#!/usr/bin/env python3
"""Peer benchmark (not a test): the running-bond walls of examples/shaken_walls.rs in pymunk
(Chipmunk2D, sequential impulses, 10 iterations a step, Δt = 1 ms), and ashlar on the same
walls in the same invocation; prints both s/step and their ratio.

Usage: python3 scripts/pymunk_wall.py [--sizes 100,400] [--steps 300] [--motions rest,sine,sine3]
       [--pymunk-only]

`--pymunk-only` skips the ashlar side (for timing the two whole processes side by side, e.g.
`farm-bench --vs 'python3 scripts/pymunk_wall.py --pymunk-only …' -- target/release/examples/shaken_walls …`).

The script creates a virtual environment in target/pymunk-venv and installs pymunk 7.3.0 from
the Python package index into it (once), then re-runs itself inside it. The ashlar side is
`cargo run --release --example shaken_walls` with the same sizes, motions and steps.

Same wall: 0.6 × 0.3 m stones of density 2500 kg/m³ (per metre of thickness) in running bond
(odd courses start and end with half stones) on a fixed foundation, friction tan 35°, gravity
9.81 m/s². The base sines (1 m/s² at 1 Hz; `sine3`: 3 m/s² at 2 Hz) enter both as the inertial load −m·a_g(t) of a
fixed-base frame (pymunk: the horizontal gravity component). pymunk's stones are rigid with
its default collision slop (0.1 mm penetration allowed) and no restitution. ashlar's example
settles its wall under gravity before the motion and counts only the steps under it; pymunk's
wall is timed from its first step (it settles onto its slop within a few steps).
"""
import math, os, re, subprocess, sys, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VENV = os.path.join(ROOT, "target", "pymunk-venv")
PYMUNK = "pymunk==7.3.0"


def arg(name, default):
    if name in sys.argv:
        return sys.argv[sys.argv.index(name) + 1]
    return default


def ensure_pymunk():
    try:
        import pymunk  # noqa: F401
        return
    except ImportError:
        pass
    py = os.path.join(VENV, "bin", "python")
    if os.environ.get("ASHLAR_PYMUNK_VENV"):
        sys.exit("pymunk could not be imported inside " + VENV)
    if not os.path.exists(py):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
    subprocess.check_call([py, "-m", "pip", "install", "--quiet", PYMUNK])
    env = dict(os.environ, ASHLAR_PYMUNK_VENV="1")
    os.execve(py, [py] + sys.argv, env)


def layout(n):
    """Same as examples/shaken_walls.rs: courses and whole stones a course."""
    side = max(int(round(math.sqrt(n))), 2)
    return side, side


def build(pymunk, n):
    space = pymunk.Space()
    space.iterations = 10
    space.gravity = (0.0, -9.81)
    l, h, rho, mu = 0.6, 0.3, 2500.0, math.tan(math.radians(35.0))
    courses, per = layout(n)
    width = l * per
    ground = pymunk.Segment(space.static_body, (-0.5, 0.0), (width + 0.5, 0.0), 0.0)
    ground.friction = mu
    space.add(ground)
    stones = 0
    for c in range(courses):
        pieces = [0.5 * l] + [l] * (per - 1) + [0.5 * l] if c % 2 else [l] * per
        x = 0.0
        for w in pieces:
            mass = rho * w * h
            body = pymunk.Body(mass, pymunk.moment_for_box(mass, (w, h)))
            body.position = (x + 0.5 * w, c * h + 0.5 * h)
            shape = pymunk.Poly.create_box(body, (w, h), 0.0)
            shape.friction = mu
            space.add(body, shape)
            x += w
            stones += 1
    return space, stones


def run_pymunk(n, motion, steps):
    import pymunk
    space, stones = build(pymunk, n)
    dt = 1e-3
    t0 = time.perf_counter()
    for k in range(steps):
        t = (k + 1) * dt
        ag = {"sine": 1.0 * math.sin(2.0 * math.pi * t),
              "sine3": 3.0 * math.sin(2.0 * math.pi * 2.0 * t)}.get(motion, 0.0)
        space.gravity = (-ag, -9.81)
        space.step(dt)
    return stones, (time.perf_counter() - t0) / steps


def run_ashlar(sizes, motions, steps):
    cmd = ["cargo", "run", "--release", "--quiet", "--example", "shaken_walls", "--",
           "--sizes", ",".join(map(str, sizes)), "--motions", ",".join(motions),
           "--steps", str(steps)]
    out = subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True, text=True).stdout
    rows = {}
    for line in out.splitlines():
        m = re.match(r"\| (\d+) \| (\w+) \| (\d+) \| ([0-9.e+-]+) \| ([0-9.]+) \|", line)
        if m:
            rows[(int(m.group(1)), m.group(2))] = (float(m.group(4)), float(m.group(5)))
    return rows


def main():
    ensure_pymunk()
    sizes = [int(s) for s in arg("--sizes", "100,400").split(",")]
    motions = arg("--motions", "rest,sine").split(",")
    steps = int(arg("--steps", "300"))
    for m in motions:
        if m not in ("rest", "sine", "sine3"):
            sys.exit(f"--motions: {m!r} (pymunk side supports rest, sine, sine3)")
    ash = {} if "--pymunk-only" in sys.argv else run_ashlar(sizes, motions, steps)
    print("| stones | motion | steps | ashlar s/step | linear solves/step | pymunk s/step (10 iterations) | ashlar / pymunk |")
    print("|---|---|---|---|---|---|---|")
    for n in sizes:
        for m in motions:
            stones, pm = run_pymunk(n, m, steps)
            a = ash.get((stones, m))
            if a is None:
                print(f"| {stones} | {m} | {steps} | (no ashlar row) | | {pm:.3e} | |")
                continue
            print(f"| {stones} | {m} | {steps} | {a[0]:.3e} | {a[1]:.2f} | {pm:.3e} | {a[0] / pm:.2f} |")


if __name__ == "__main__":
    main()
