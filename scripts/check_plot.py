#!/usr/bin/env python3
"""Check plot files made by the scripts: each exists, went through the data check and
is not blank.

    python scripts/check_plot.py FILE...

The scripts save every figure through scripts/plot_common.py's `save`, which refuses a
figure with a data panel that holds no data and stamps the file it writes (PNG and
SVG `Description`, PDF `Subject`). This checks the files: the stamp is there (so the
check ran: a file saved around it fails), a PNG decodes and is not uniform, an SVG
holds drawing paths, a PDF is one. Exits 1 naming every file that fails. PNG needs
pillow and numpy.
"""

import pathlib
import sys

from plot_common import STAMP


def png_problem(path):
    import numpy as np
    from PIL import Image

    with Image.open(path) as im:
        stamp = im.info.get("Description", "")
        a = np.asarray(im.convert("RGB"), dtype=int)
    if stamp != STAMP:
        return "not stamped by plot_common.save: its panels were not checked for data"
    away = np.abs(a - a[0, 0]).sum(axis=2) > 30
    if away.mean() < 0.005:
        return f"blank: only {100 * away.mean():.2f} % of its pixels are not background"
    return None


def vector_problem(path):
    data = pathlib.Path(path).read_bytes()
    if STAMP.encode() not in data:
        return "not stamped by plot_common.save: its panels were not checked for data"
    if path.suffix == ".svg":
        n = data.count(b"<path")
        return None if n >= 10 else f"only {n} path(s): blank"
    if not data.startswith(b"%PDF"):
        return "not a PDF"
    return None if len(data) > 2000 else "too small to hold a plot"


def main():
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    bad = 0
    for name in sys.argv[1:]:
        path = pathlib.Path(name)
        if not path.is_file() or path.stat().st_size == 0:
            problem = "missing or empty"
        elif path.suffix == ".png":
            problem = png_problem(path)
        elif path.suffix in (".pdf", ".svg"):
            problem = vector_problem(path)
        else:
            problem = "not a .png, .pdf or .svg file"
        if problem:
            bad += 1
            print(f"FAIL {name}: {problem}")
        else:
            print(f"OK {name}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
