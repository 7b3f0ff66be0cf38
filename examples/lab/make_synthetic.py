#!/usr/bin/env python3
"""Writes the SYNTHETIC deposit profiles of this directory (they are not lab data).

    python examples/lab/make_synthetic.py

They exist to exercise scripts/compare_deposit.py and to show the CSV formats of
docs/validation.md: a made-up smooth deposit on a 22° plane,
    h_n(X) = 0.04 · (1 − ((X − 0.35)/0.75)²)^¾   (m, normal to the plane),
written twice: along the slope (X, h_n) and seen from a horizontal frame
(x = X cos 22°, h_v = h_n / cos 22°), so that both files describe the same deposit.
A third file gives the free-surface elevation z = h_n on a flat bed (x,z format).
"""

import math
import pathlib

HERE = pathlib.Path(__file__).resolve().parent
C = math.cos(math.radians(22.0))


def h_n(x):
    s = 1.0 - ((x - 0.35) / 0.75) ** 2
    return 0.04 * s ** 0.75 if s > 0 else 0.0


def main():
    xs = [-0.2 + 0.025 * i for i in range(57)]  # -0.2 … 1.2 m
    note = "# SYNTHETIC deposit, not lab data: examples/lab/make_synthetic.py\n"
    files = {
        "synthetic_deposit_along_slope.csv": ("x,h", [(x, h_n(x)) for x in xs]),
        "synthetic_deposit_horizontal.csv": ("x,h", [(x * C, h_n(x) / C) for x in xs]),
        "synthetic_surface_along_slope.csv": ("x,z", [(x, h_n(x)) for x in xs]),
    }
    for name, (header, rows) in files.items():
        with open(HERE / name, "w") as f:
            f.write(note + f"# frame: {'horizontal' if 'horizontal' in name else 'along-slope'}\n")
            f.write(header + "\n")
            for x, v in rows:
                f.write(f"{x:.6f},{v:.6f}\n")
        print(HERE / name)


if __name__ == "__main__":
    main()
