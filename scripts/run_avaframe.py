"""Run AvaFrame com1DFA on its hockey-stick or helix example with Voellmy friction, as
docs/validation.md ("AvaFrame's standard avalanches") compares it with granflow.

Needs AvaFrame (`pip install avaframe==2.1`, in a virtual environment of its own) and
a clone of its repository (github.com/avaframe/AvaFrame) for the release areas
(avaframe/data/avaHockeyChannel/Inputs/REL/release1HS.*,
avaframe/data/avaHelixChannel/Inputs/REL/release1HX.*). The DEM is written by
AvaFrame's own in3Utils/generateTopo (type HS or HX, its defaults with yEnd = 2000 m:
the examples' grid of 1001 x 401 cells of 5 m). The simulation: simTypeList = null (no
entrainment or resistance areas), frictModel = Voellmy with mu = 0.155 and
xsi = 4000 m/s^2, meshCellSize = CELL, curvAccInFriction = 1 or 0, every other key
AvaFrame's default (stop at 1 % of the peak kinetic energy). The peak rasters land in
WORKDIR/<case>_<cell>m_curv<0|1>/Outputs/com1DFA/peakFiles, with timing.json (wall and
CPU seconds) beside Outputs.

Usage (with AvaFrame's Python):
    python scripts/run_avaframe.py --case hockey --cell 5 --curvature 1 \
        --avaframe-repo AvaFrame --workdir runs
"""

import argparse
import json
import pathlib
import resource
import shutil
import time

EXAMPLE = {"hockey": ("HS", "avaHockeyChannel", "release1HS"),
           "helix": ("HX", "avaHelixChannel", "release1HX")}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--case", choices=tuple(EXAMPLE), required=True)
    ap.add_argument("--cell", type=float, default=5.0, help="meshCellSize, m")
    ap.add_argument("--curvature", choices=("0", "1"), default="1",
                    help="curvAccInFriction (1, AvaFrame's default)")
    ap.add_argument("--avaframe-repo", required=True, type=pathlib.Path,
                    help="a clone of github.com/avaframe/AvaFrame (for the release areas)")
    ap.add_argument("--workdir", type=pathlib.Path, default=pathlib.Path("."))
    args = ap.parse_args()

    from avaframe.com1DFA import com1DFA
    from avaframe.in3Utils import cfgUtils, logUtils
    from avaframe.in3Utils import generateTopo

    dem_type, example, release = EXAMPLE[args.case]
    cell = f"{args.cell:g}"
    ava = (args.workdir / f"{args.case}_{cell}m_curv{args.curvature}").resolve()
    if ava.exists():
        shutil.rmtree(ava)
    for sub in ("REL", "ENT", "RES", "LINES", "POINTS"):
        (ava / "Inputs" / sub).mkdir(parents=True)

    topo = cfgUtils.getModuleConfig(generateTopo)
    topo["TOPO"]["demType"] = dem_type
    topo["TOPO"]["yEnd"] = "2000"
    generateTopo.generateTopo(topo, ava)

    rel = args.avaframe_repo / "avaframe" / "data" / example / "Inputs" / "REL"
    copied = [shutil.copy(p, ava / "Inputs" / "REL") for p in rel.glob(release + ".*")]
    if not copied:
        raise SystemExit(f"error: no {release}.* in {rel}")

    main_cfg = cfgUtils.getGeneralConfig()
    main_cfg["MAIN"]["avalancheDir"] = str(ava)
    main_cfg["MAIN"]["nCPU"] = "1"
    main_cfg["FLAGS"]["createReport"] = "False"
    main_cfg["FLAGS"]["savePlot"] = "False"
    logUtils.initiateLogger(str(ava), "run_avaframe")
    cfg = cfgUtils.getModuleConfig(com1DFA, str(ava), toPrint=False)
    general = cfg["GENERAL"]
    general["simTypeList"] = "null"
    general["frictModel"] = "Voellmy"
    general["muvoellmy"] = "0.155"
    general["xsivoellmy"] = "4000."
    general["meshCellSize"] = cell
    general["curvAccInFriction"] = args.curvature

    wall, cpu = time.time(), time.process_time()
    com1DFA.com1DFAMain(main_cfg, cfgInfo=cfg)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    timing = {"wall_s": time.time() - wall,
              "cpu_s": time.process_time() - cpu + children.ru_utime + children.ru_stime}
    (ava / "timing.json").write_text(json.dumps(timing) + "\n")
    print(f"{ava}: {timing}")


if __name__ == "__main__":
    main()
