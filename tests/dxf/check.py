#!/usr/bin/env python3
"""Import every drawing of a directory written by make_drawings.py with the real binary
(`ashlar scene import`) and compare with what make_drawings.py expects: every block's id, fixed
flag and vertices (within 1e-9 m, the issue's target), every bad drawing refused naming its
entity handle and layer.

    python3 tests/dxf/check.py path/to/ashlar DIR
"""
import json
import os
import subprocess
import sys
import tempfile

TOL = 1e-9
binary, folder = sys.argv[1], sys.argv[2]
names = sorted(n[:-4] for n in os.listdir(folder) if n.endswith(".dxf"))
failures = []
checked = 0
for name in names:
    exp = json.load(open(os.path.join(folder, name + ".json")))
    cmd = [binary, "scene", "import", os.path.join(folder, name + ".dxf")]
    opts = None
    if "options" in exp:
        opts = tempfile.NamedTemporaryFile("w", suffix=".json", delete=False)
        json.dump(exp["options"], opts)
        opts.close()
        cmd += ["--options", opts.name]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if opts:
        os.unlink(opts.name)
    checked += 1
    if "error" in exp:
        if r.returncode == 0:
            failures.append(f"{name}: imported, expected {exp['error']}")
        elif "handle" in exp and f'entity {exp["handle"]} on layer "{exp["layer"]}"' not in r.stderr:
            failures.append(f"{name}: the error does not name entity {exp['handle']} on layer {exp['layer']}: {r.stderr.strip()}")
        continue
    if r.returncode != 0:
        failures.append(f"{name}: refused: {r.stderr.strip()}")
        continue
    scene = json.loads(r.stdout)
    blocks = scene["blocks"]
    if len(blocks) != len(exp["blocks"]):
        failures.append(f"{name}: {len(blocks)} blocks, expected {len(exp['blocks'])}")
        continue
    worst = 0.0
    for b, e in zip(blocks, exp["blocks"]):
        if b["id"] != f'{e["layer"]}-{e["handle"]}' or b.get("fixed", False) != e["fixed"]:
            failures.append(f"{name}: block {b['id']} (fixed {b.get('fixed')}), expected {e['layer']}-{e['handle']} (fixed {e['fixed']})")
            continue
        if len(b["vertices"]) != len(e["vertices"]):
            failures.append(f"{name}: {b['id']}: {len(b['vertices'])} vertices, expected {len(e['vertices'])}")
            continue
        for v, w in zip(b["vertices"], e["vertices"]):
            worst = max(worst, abs(v[0] - w[0]), abs(v[1] - w[1]))
    if worst > TOL:
        failures.append(f"{name}: a vertex is {worst:.3e} m off (tolerance {TOL} m)")
    print(f"dxf: {name}: {len(blocks)} blocks, largest vertex error {worst:.3e} m")
for f in failures:
    print("dxf: FAILED:", f, file=sys.stderr)
print(f"dxf: {checked - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures or checked == 0 else 0)
