#!/usr/bin/python3
"""Write the shipped contact example: meshes/examples/organ_table_instrument.json.

The disk-shaped organ (meshes/disk_organ_1k.msh, made by scripts/gen_meshes.py: an ellipsoid with
semi-axes 1, 0.8, 0.3 m) is attached at one end (the vertices with x < -0.85 held, a ligament) and
lies over a frictionless table 2 cm below it.  A spherical instrument (radius 0.3 m) comes down
onto its top near the attached end, then slides across it to the other end, pressing the organ
onto the table: contact as physics, the contact areas on the tool and on the table found every
frame (docs/contact.md).

Usage:
    /usr/bin/python3 scripts/make_contact_example.py [--out FILE] [--frames N]
"""

import argparse
import json
import os

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def frames(n, descend=8, depth=0.1, start=-0.5, end=0.6):
    """The tool's offsets: down by `depth` over `descend` frames, then across in x."""
    out = []
    for i in range(n):
        if i < descend:
            dx, dz = 0.0, depth * (i + 1) / descend
        else:
            dx, dz = (end - start) * (i - descend + 1) / (n - descend), depth
        out.append({"obstacles": {"tool": {"translate": [round(dx, 6), 0, round(-dz, 6)]}}})
    return out


def problem(n):
    return {
        "mesh": "../disk_organ_1k.msh",
        "material": {"E": 3000.0, "nu": 0.45},
        "boundary": [{"where": {"box": [[-1.1, -1, -1], [-0.85, 1, 1]]}, "displacement": [0, 0, 0]}],
        "contact": {
            "obstacles": [
                {"name": "table", "plane": {"point": [0, 0, -0.32], "normal": [0, 0, 1]}},
                {"name": "tool", "sphere": {"center": [-0.5, 0, 0.55], "radius": 0.3}},
            ],
            "friction": 0.0,
        },
        "frames": frames(n),
        "output": "organ_table_instrument.h5",
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(REPO, "meshes", "examples", "organ_table_instrument.json"))
    ap.add_argument("--frames", type=int, default=32)
    args = ap.parse_args()
    head = ("// Contact as physics (docs/contact.md): a disk-shaped organ attached at one end, over a\n"
            "// frictionless table, pressed and swept by a spherical instrument. Written by\n"
            "// scripts/make_contact_example.py.\n")
    with open(args.out, "w") as f:
        f.write(head + json.dumps(problem(args.frames), indent=1) + "\n")
    print("wrote %s (%d frames)" % (args.out, args.frames))


if __name__ == "__main__":
    main()
