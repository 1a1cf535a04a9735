#!/usr/bin/env python3
"""Write the DXF test drawings of `ashlar scene import` with ezdxf, a CAD library independent of
the `dxf` crate that ashlar reads them with (docs/import.md).

    python3 tests/dxf/make_drawings.py OUT_DIR

writes into OUT_DIR, for each drawing NAME:
  NAME.dxf     the drawing;
  NAME.json    what importing it must give: for a good drawing its unit and every block (the
               entity handle as ezdxf assigned it, layer, fixed or not, vertices in metres in the
               drawing's order, computed here from the coordinates given to ezdxf); for a bad one
               the error kind and the handle and layer it must name.
The files checked in under tests/fixtures/dxf/ were written by this script (ezdxf 1.4); the Rust
tests (tests/inputs/scene_dxf.rs) read those, so `cargo test` needs no network. CI's dxf stage
writes them anew with ezdxf from the Python package index and imports them with the binary
(tests/dxf/check.py).
"""
import json
import math
import os
import sys

import ezdxf
from ezdxf.math import OCS

OUT = sys.argv[1] if len(sys.argv) > 1 else "tests/fixtures/dxf"
os.makedirs(OUT, exist_ok=True)

INSUNITS = {"in": 1, "ft": 2, "mm": 4, "cm": 5, "m": 6}
TO_M = {"mm": lambda v: v / 1000.0, "cm": lambda v: v / 100.0, "m": lambda v: v, "ft": lambda v: v * 0.3048}


def new(units, version="R2013"):
    doc = ezdxf.new(version)
    if units is not None:
        doc.header["$INSUNITS"] = INSUNITS[units]
    return doc


def save(doc, name, expected):
    doc.saveas(os.path.join(OUT, name + ".dxf"))
    with open(os.path.join(OUT, name + ".json"), "w") as f:
        json.dump(expected, f, indent=1)
        f.write("\n")


class Good:
    """A drawing that must import; records each block as it is drawn."""

    def __init__(self, units, version="R2013", read_as=None):
        self.doc = new(units, version)
        self.msp = self.doc.modelspace()
        self.units = units or read_as or "m"
        self.blocks = []

    def record(self, entity, layer, wcs_points):
        conv = TO_M[self.units]
        self.blocks.append({
            "handle": entity.dxf.handle,
            "layer": layer,
            "fixed": layer.lower() == "fixed",
            "vertices": [[conv(x), conv(y)] for x, y in wcs_points],
        })

    def lw(self, layer, pts, close=True, extra_closing=False):
        drawn = list(pts) + ([pts[0]] if extra_closing else [])
        e = self.msp.add_lwpolyline(drawn, close=close, dxfattribs={"layer": layer})
        self.record(e, layer, pts)
        return e

    def poly2d(self, layer, pts, extra_closing=False):
        drawn = list(pts) + ([pts[0]] if extra_closing else [])
        e = self.msp.add_polyline2d(drawn, close=True, dxfattribs={"layer": layer})
        self.record(e, layer, pts)
        return e

    def mirrored_lw(self, layer, wcs_pts):
        """An LWPOLYLINE with extrusion (0, 0, -1), as CAD programs write a mirrored one: its
        points are in the object coordinate system, converted here by ezdxf's own OCS."""
        ocs = OCS((0, 0, -1))
        ocs_pts = [tuple(ocs.from_wcs((x, y, 0)))[:2] for x, y in wcs_pts]
        e = self.msp.add_lwpolyline(ocs_pts, close=True, dxfattribs={"layer": layer, "extrusion": (0, 0, -1)})
        back = [tuple(ocs.to_wcs((x, y, 0)))[:2] for x, y in ocs_pts]
        self.record(e, layer, back)
        return e

    def save(self, name, options=None):
        exp = {"units": self.units, "blocks": self.blocks}
        if options is not None:
            exp["options"] = options
        save(self.doc, name, exp)


def rect(x0, y0, x1, y1):
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


# 1. A wall of rectangles in running bond, in millimetres, LWPOLYLINE; the foundation on the layer
# "FIXED" (any case marks fixed blocks); the whole drawing offset so coordinates are not round.
g = Good("mm")
ox, oy = 1234.5678, 876.54321
length, height, course_h, stone = 2400.0, 1000.0, 250.0, 600.0
g.lw("FIXED", rect(ox - 300.0, oy - 500.0, ox + length + 300.0, oy))
for c in range(4):
    y0, y1 = oy + c * course_h, oy + (c + 1) * course_h
    cuts = [0.0, 600.0, 1200.0, 1800.0, 2400.0] if c % 2 == 0 else [0.0, 300.0, 900.0, 1500.0, 2100.0, 2400.0]
    for a, b in zip(cuts, cuts[1:]):
        g.lw("limestone", rect(ox + a, y0, ox + b, y1))
g.save("wall_mm")

# 2. A semicircular arch of 9 voussoirs on two piers, in metres: voussoir joints radial, corners
# on circles (coordinates irrational).
g = Good("m", "R2010")
R, t, n, spring = 2.0, 0.4, 9, 1.5
ri, ro = R - t / 2, R + t / 2
g.lw("fixed", rect(-3.0, -0.5, 3.0, 0.0))
g.lw("limestone", rect(ri - 0.1, 0.0, ro + 0.1, spring))
g.lw("limestone", rect(-ro - 0.1, 0.0, -ri + 0.1, spring))
for k in range(n):
    a0, a1 = math.pi * k / n, math.pi * (k + 1) / n
    pts = [(ri * math.cos(a0), spring + ri * math.sin(a0)), (ro * math.cos(a0), spring + ro * math.sin(a0)),
           (ro * math.cos(a1), spring + ro * math.sin(a1)), (ri * math.cos(a1), spring + ri * math.sin(a1))]
    g.lw("marble", pts)
g.save("arch_m")

# 3. Old-style POLYLINE (AcDb2dPolyline with VERTEX entities), R2000, in centimetres: a column of
# drums; one drum drawn clockwise, one with its first vertex repeated at the end; the capital an
# LWPOLYLINE mirrored (extrusion −z); a TEXT note on its own layer (an annotation, skipped).
g = Good("cm", "R2000")
g.poly2d("fixed", rect(-60.0, -40.0, 60.0, 0.0))
h = 80.25
g.poly2d("marble", rect(-30.0, 0.0, 30.0, h))
g.poly2d("marble", list(reversed(rect(-29.0, h, 29.0, 2 * h))))
g.poly2d("marble", rect(-28.0, 2 * h, 28.0, 3 * h), extra_closing=True)
g.mirrored_lw("marble", rect(-40.0, 3 * h, 40.0, 3 * h + 25.5))
g.msp.add_text("column, survey 2026", dxfattribs={"layer": "notes", "insert": (50.0, 50.0)})
g.save("column_polyline_cm")

# 4. No $INSUNITS (an R12 drawing: the variable does not exist there), read with the options'
# units "mm"; an open LWPOLYLINE is not possible in R12, so POLYLINEs.
g = Good(None, "R12", read_as="mm")
g.poly2d("fixed", rect(0.0, -500.0, 1000.0, 0.0))
g.poly2d("stone", rect(250.0, 0.0, 750.0, 1500.0))
g.save("unitless_r12", options={"units": "mm"})


# Bad drawings: each must be refused naming the entity's handle and layer.
def bad(name, kind, build, units="m"):
    doc = new(units)
    msp = doc.modelspace()
    msp.add_lwpolyline(rect(-1.0, -0.5, 1.0, 0.0), close=True, dxfattribs={"layer": "fixed"})
    culprit, other = build(msp)
    exp = {"error": kind, "handle": culprit.dxf.handle, "layer": culprit.dxf.layer}
    if other is not None:
        exp["other_handle"] = other.dxf.handle
        exp["other_layer"] = other.dxf.layer
    save(doc, name, exp)


bad("bad_open", "open", lambda m: (m.add_lwpolyline(rect(0, 0, 0.4, 1.2), close=False, dxfattribs={"layer": "stone"}), None))
bad("bad_arc", "curve", lambda m: (m.add_lwpolyline(rect(0, 0, 0.4, 1.2), close=True, dxfattribs={"layer": "stone"})
                                   and m.add_arc((0.2, 1.2), 0.2, 0, 180, dxfattribs={"layer": "arches"}), None))
bad("bad_circle", "curve", lambda m: (m.add_circle((0.0, 0.5), 0.5, dxfattribs={"layer": "drums"}), None))
bad("bad_spline", "curve", lambda m: (m.add_spline([(0, 0), (0.5, 0.5), (1, 0), (1.5, 1)], dxfattribs={"layer": "mouldings"}), None))
bad("bad_bulge", "bulge", lambda m: (m.add_lwpolyline([(0, 0, 0, 0, 0), (0.4, 0, 0, 0, 0), (0.4, 1.2, 0, 0, 0.5), (0, 1.2, 0, 0, 0)],
                                                      format="xyseb", close=True, dxfattribs={"layer": "stone"}), None))
bad("bad_two_vertices", "too_few_vertices", lambda m: (m.add_lwpolyline([(0, 0), (0.4, 1.2)], close=True, dxfattribs={"layer": "stone"}), None))
bad("bad_self_intersecting", "block", lambda m: (m.add_lwpolyline([(0, 0), (0.4, 1.2), (0.4, 0), (0, 1.2)], close=True, dxfattribs={"layer": "stone"}), None))


def overlap(m):
    a = m.add_lwpolyline(rect(-0.2, 0.0, 0.2, 1.2), close=True, dxfattribs={"layer": "stone"})
    b = m.add_lwpolyline(rect(0.1, 0.0, 0.5, 1.2), close=True, dxfattribs={"layer": "marble"})
    return b, a


bad("bad_overlap", "overlap", overlap)
bad("bad_line", "unsupported", lambda m: (m.add_line((0, 0), (1, 1), dxfattribs={"layer": "construction"}), None))

doc = new("m")
doc.modelspace().add_text("nothing drawn", dxfattribs={"layer": "notes"})
save(doc, "bad_empty", {"error": "empty"})

with open(os.path.join(OUT, "bad_garbage.dxf"), "w") as f:
    f.write("this is not a DXF file\n0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\nmillimetres\n")
with open(os.path.join(OUT, "bad_garbage.json"), "w") as f:
    json.dump({"error": "unreadable"}, f)
    f.write("\n")
print(f"make_drawings: ezdxf {ezdxf.__version__}: drawings written to {OUT}")
