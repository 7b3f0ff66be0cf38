#!/usr/bin/env python3
"""Regenerate the measured results quoted in the docs from a run of this checkout.

    python scripts/doc_results.py [--list] [ID ...]

The docs hold blocks delimited by
    <!-- result: ID -->
    …
    <!-- end result: ID -->
(docs/validation.md, docs/sweeps.md). This script runs the command behind each ID
(a `cargo test` with --nocapture, whose printed lines are the measured numbers, or a
granflow command or script), and replaces the block with its output, the command
and whether it passed. Without IDs, all blocks; --list prints the IDs. The block
`provenance` records the commit, the date and the machine. Numbers in those blocks
therefore always come from a run; rerun this after a change to the numerics (for
example to the CFL time step, which changes step counts).
Needs the Python of the comparison scripts (h5py, numpy, matplotlib) as `python`
on PATH or as this script's interpreter; builds with cargo.
"""

import os
import pathlib
import platform
import re
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
DOCS = [ROOT / "docs/validation.md", ROOT / "docs/sweeps.md"]
GRANFLOW = ROOT / "target/release/granflow"


def cargo_test(module, name):
    # The integration tests are one crate, tests/main.rs, with a module per area;
    # --include-ignored runs the slow tier's tests too (`#[ignore = "slow: …"]`).
    return ["cargo", "test", "--test", "main", f"{module}::{name}", "--", "--exact",
            "--include-ignored", "--nocapture", "--test-threads=1"]


# ID -> the command run (shown in the docs with {tmp} as out)
CHECKS = {
    "ritter": cargo_test("analytic", "ritter_dry_dam_break_converges"),
    "similarity_frictionless": cargo_test(
        "terrain_2d_reference", "frictionless_similarity_solution_on_an_inclined_plane_converges"),
    "similarity_coulomb": cargo_test(
        "terrain_2d_reference", "coulomb_similarity_solution_on_an_inclined_plane_converges"),
    "coulomb_pile": cargo_test(
        "terrain_2d_reference", "coulomb_cone_collapses_into_a_pile_at_its_repose_slope"),
    "energy_line": cargo_test(
        "terrain_2d_reference", "coulomb_mass_on_a_curved_thalweg_stops_on_its_energy_line"),
    "centrifugal": cargo_test(
        "terrain_2d_reference", "centrifugal_term_on_the_curved_thalweg_steepens_the_travel_angle"),
    "radial_layers": cargo_test(
        "multilayer_2d_scenario", "radial_collapse_with_ten_layers_against_one_converges_with_dx"),
    "rotation": cargo_test(
        "terrain_2d", "rotated_releases_agree_within_a_tolerance_that_shrinks_with_the_cell_size"),
    "stoker": cargo_test("analytic", "stoker_wet_dam_break_converges"),
    "dam_break_script": ["python", "scripts/compare_dam_break.py", "--out", "{tmp}/dam_break"],
    "coulomb_stop": cargo_test(
        "analytic", "coulomb_friction_decelerates_as_the_ode_and_stops_without_reversal"),
    "coulomb_accelerates": cargo_test("analytic", "coulomb_friction_below_slope_accelerates_as_the_ode"),
    "cartesian_slope": cargo_test(
        "analytic", "cartesian_layer_on_a_sloped_bed_accelerates_at_g_tan_theta_minus_mu"),
    "random_bed_rest": cargo_test(
        "well_balanced", "granular_mass_at_repose_angle_on_random_bed_stays_at_rest"),
    "random_bed_moves": cargo_test("well_balanced", "granular_mass_just_beyond_repose_angle_moves"),
    "lake_submerged": cargo_test("well_balanced", "frictionless_lake_at_rest_over_submerged_bump"),
    "lake_emerged": cargo_test("well_balanced", "frictionless_lake_at_rest_with_emerged_bump"),
    "mass_walls": cargo_test("conservation", "granular_collapse_between_walls_conserves_mass"),
    "mass_dam_walls": cargo_test(
        "conservation", "frictionless_dam_break_reflecting_on_walls_conserves_mass"),
    "bagnold": cargo_test("multilayer", "bagnold_profile_converges_at_second_order_in_the_layers"),
    "sidewall": cargo_test("multilayer", "sidewall_profiles_match_jop_solution"),
    "ml_rest": cargo_test("multilayer", "multilayer_mass_at_repose_stays_at_rest_to_order_delta"),
    "ml_creep": cargo_test("multilayer", "creep_at_rest_follows_the_frozen_viscosity_recursion"),
    "erodible": cargo_test(
        "multilayer", "erodible_bed_lengthens_runout_with_mu_i_but_not_with_constant_friction"),
    "erodible_cmsm": cargo_test("multilayer", "erodible_bed_lengthens_runout_with_c_msm"),
    "erodible_stop_19": cargo_test(
        "multilayer",
        "erodible_bed_at_19_degrees_bulk_flow_ends_later_and_creep_earlier_on_a_thicker_bed"),
    "erodible_sweep": ["sh", "-c",
                       "granflow sweep scenarios/sweeps/erodible_bed.toml --jobs 2 --quiet "
                       "--output {tmp}/erodible && "
                       "python scripts/compare_erodible_lab.py {tmp}/erodible"],
    "erodible_monolayer": ["sh", "-c",
                           "for s in layer bagnold; do echo \"monolayer_shear = $s:\"; "
                           "granflow sweep scenarios/sweeps/erodible_bed.toml --jobs 2 --quiet "
                           "--output {tmp}/erodible_$s --set model.layers=1 "
                           "--set rheology.monolayer_shear=$s && "
                           "python scripts/compare_erodible_lab.py {tmp}/erodible_$s || exit 1; done"],
    "nh_constraint": cargo_test("nonhydrostatic", "discrete_constraint_holds_after_every_projection"),
    "nh_rest": cargo_test("nonhydrostatic", "granular_mass_at_rest_keeps_q_exactly_zero"),
    "nh_wedge": cargo_test("nonhydrostatic", "wedge_hydrostatic_local_runout_exceeds_nonhydrostatic"),
    "nh_front": cargo_test(
        "nonhydrostatic", "collapse_front_velocity_nh_accelerates_then_decays_h_starts_fastest"),
    "nh_gate": cargo_test(
        "nonhydrostatic", "gate_slows_the_start_and_raises_the_peak_of_the_front_velocity"),
    "nh_deposits": cargo_test(
        "nonhydrostatic", "nh_cartesian_and_h_local_deposits_are_close_while_dynamics_differ"),
    "dil_k0": cargo_test("dilatant", "without_dilatancy_the_run_is_the_savage_hutter_run_bit_for_bit"),
    "dil_rest": cargo_test("dilatant", "split_scheme::masses_at_rest_below_repose_stay_exactly_at_rest"),
    "dil_mass": cargo_test("dilatant", "split_scheme::grains_are_conserved_and_fractions_stay_admissible"),
    "dil_collapse": cargo_test("dilatant", "section_4_3_with_the_default_scheme"),
    "dil_threshold": cargo_test("dilatant", "split_scheme::static_thresholds_follow_the_dilatant_friction"),
    "dil_uniform": cargo_test("dilatant", "split_scheme::uniform_flow_on_an_incline_reaches_the_critical_state_split_scheme"),
    "dil_odd_even": cargo_test(
        "dilatant", "split_scheme::an_odd_even_fraction_pattern_on_a_flat_layer_is_no_equilibrium"),
    "dil_rest_10": cargo_test("dilatant", "split_scheme::dense_collapse_at_10_degrees_comes_to_rest"),
    "dil_thin": cargo_test("dilatant", "split_scheme::layers_thinner_than_the_threshold_do_not_dilate"),
    "dil_thin_convergence": cargo_test(
        "dilatant", "early_front_and_peak_dilation_converge_with_the_thickness_threshold"),
    "dil_slopes": cargo_test("dilatant", "fig_9a_front_order_on_the_five_slopes"),
    "dil_settle": cargo_test("dilatant", "collapses_come_to_rest_and_settle_at_converging_times"),
    "dil_contraction": cargo_test("dilatant", "front_contraction_and_peak_velocity_at_0_degrees"),
    "collapse_pins": cargo_test("scenarios", "collapse_regression_norms"),
    "frozen_hashes": cargo_test("multilayer", "monolayer_numbers_are_frozen"),
    "film_speed": cargo_test("properties", "thin_cell_next_to_a_bed_step_keeps_a_bounded_speed"),
    "sweep_slopes": ["granflow", "sweep", "scenarios/sweeps/slopes.toml", "--jobs", "2",
                     "--output", "{tmp}/slopes"],
}

NOISE = re.compile(r"^(running \d+ tests?|test result:|\s*(Compiling|Finished|Running|"
                   r"Blocking|Doc-tests)\b|successes:|failures:|---- |$)")


def run(id_, tmp):
    cmd = [c.replace("{tmp}", tmp) for c in CHECKS[id_]]
    env = dict(os.environ, CARGO_TERM_COLOR="never", PATH=f"{GRANFLOW.parent}:{os.environ['PATH']}")
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=env)
    # A test's numbers are on stdout (println) or stderr (eprintln); a script's on stdout.
    out = (p.stdout + "\n" + p.stderr if cmd[0] == "cargo" else p.stdout).splitlines()
    lines = [l.rstrip() for l in out if not NOISE.match(l)]
    lines = [l.replace(tmp, "out") for l in lines]
    status = "passed" if p.returncode == 0 else f"FAILED (exit {p.returncode})"
    if cmd[0] == "cargo":
        # libtest's own words around the test's output: "test NAME ... " and "ok".
        lines = [re.sub(r"^test \S+ \.\.\. ", "", l) for l in lines]
        lines = [l for l in lines if l not in ("", "ok")]
    return status, lines


def shown(id_):
    c = " ".join(CHECKS[id_])
    if CHECKS[id_][0] == "sh":
        c = CHECKS[id_][2]
    return c.replace("{tmp}", "out").replace(" --nocapture --test-threads=1", " --nocapture")


def block(id_, tmp):
    if id_ == "provenance":
        return provenance()
    status, lines = run(id_, tmp)
    print(f"{id_}: {status}", file=sys.stderr)
    body = "\n".join(lines) if lines else "(the test prints nothing; it passes when its assertions hold)"
    return f"`{shown(id_)}` — {status}\n\n```text\n{body}\n```\n"


def provenance():
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip()
    # The docs this script writes do not count as changes to what was measured.
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ".",
                            *(f":!{d.relative_to(ROOT)}" for d in DOCS)], cwd=ROOT,
                           capture_output=True, text=True).stdout.strip()
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo")
                if l.startswith("model name")), platform.processor())
    mem = next((int(l.split()[1]) for l in open("/proc/meminfo") if l.startswith("MemTotal")), 0)
    date = subprocess.run(["date", "-u", "+%Y-%m-%d %H:%M UTC"], capture_output=True,
                          text=True).stdout.strip()
    rustc = subprocess.run(["rustc", "--version"], capture_output=True, text=True).stdout.strip()
    return (f"Generated by `python scripts/doc_results.py` at commit `{commit}`"
            f"{' (with uncommitted changes)' if dirty else ''} on {date}: {os.cpu_count()}-vCPU "
            f"{cpu}, {mem / 2**20:.0f} GiB, {rustc}. Wall times depend on the machine's load.\n")


def main():
    args = sys.argv[1:]
    if args[:1] == ["--list"]:
        print("\n".join(["provenance", *CHECKS]))
        return 0
    unknown = [a for a in args if a not in CHECKS and a != "provenance"]
    if unknown:
        print(f"unknown IDs: {unknown}; see --list", file=sys.stderr)
        return 2
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    failed = False
    with tempfile.TemporaryDirectory() as tmp:
        for doc in DOCS:
            text = doc.read_text()
            ids = re.findall(r"<!-- result: (\w+) -->", text)
            for id_ in ids:
                if args and id_ not in args:
                    continue
                new = block(id_, tmp)
                failed |= "FAILED" in new
                text = re.sub(rf"(<!-- result: {id_} -->\n).*?(<!-- end result: {id_} -->)",
                              lambda m: m.group(1) + new + m.group(2), text, flags=re.S)
            doc.write_text(text)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
