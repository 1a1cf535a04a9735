#!/usr/bin/env python3
"""The import rule of docs/architecture.md, checked: each layer of src/ names (as `crate::X`)
only the layers its row allows, and faer is named only under src/solve/.

Test modules (from a `#[cfg(test)]` line to the file's end, where the crate keeps them) may
also use the presets, the shared scenes. Usage: `python3 scripts/check_layers.py` from the
repository; exit status 1 and one line per breach if the rule is broken.
"""
import pathlib
import re
import sys

# Per layer (a folder or file under src/), the layers it may import besides itself, as the
# "may import" column of docs/architecture.md's table; `quantity` and `plot` are shared by
# every layer.
SHARED = {"quantity", "plot"}
CORE = ["geometry", "scene", "contact", "assembly", "solve", "integrate", "simulation"]
ALLOWED = {
    "geometry": set(),
    "scene": {"geometry"},
    "motion": set(),
    "contact": {"scene", "geometry"},
    "assembly": {"scene", "geometry", "contact"},
    "solve": {"scene", "geometry", "contact", "assembly"},
    "integrate": {"geometry", "assembly"},
    "simulation": set(CORE) | {"motion"},
    "record": set(),
    "analysis": set(CORE) | {"motion", "record", "presets"},
    "service": set(CORE) | {"motion", "record", "analysis", "presets"},
    "cli": set(CORE) | {"motion", "record", "analysis", "service", "presets"},
    "presets": {"scene", "motion"},
    "quantity": set(),
    "plot": set(),
}
NAME = re.compile(r"crate::([a-z_]+)")


def layer_of(path: pathlib.Path, src: pathlib.Path) -> str:
    first = path.relative_to(src).parts[0]
    return first[:-3] if first.endswith(".rs") else first


def main() -> int:
    root = pathlib.Path(__file__).resolve().parent.parent
    src = root / "src"
    breaches = []
    for path in sorted(src.rglob("*.rs")):
        layer = layer_of(path, src)
        if layer in ("lib", "main"):
            continue
        allowed = ALLOWED[layer] | SHARED | {layer}
        in_tests = False
        for number, line in enumerate(path.read_text().splitlines(), 1):
            if line.strip() == "#[cfg(test)]":
                in_tests = True
            where = f"{path.relative_to(root)}:{number}"
            if "faer" in line and layer != "solve" and not line.lstrip().startswith("//"):
                breaches.append(f"{where}: faer outside src/solve: {line.strip()}")
            for name in NAME.findall(line):
                if name in allowed or (in_tests and name == "presets"):
                    continue
                breaches.append(f"{where}: {layer} imports {name}: {line.strip()}")
    for b in breaches:
        print(b)
    return 1 if breaches else 0


if __name__ == "__main__":
    sys.exit(main())
