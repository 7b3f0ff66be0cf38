#!/usr/bin/env python3
"""Run every command quoted in README.md, docs/*.md and the scenario headers, so that
none of them can rot (called by .ci/run).

    python scripts/check_doc_commands.py [--granflow PATH] [--list] [--keep DIR]

What is a command: a line of a code block (fenced, or indented in the README), a line
of a scenario file's header comment, or an inline `code span`, that starts with
`granflow`, `python`/`python3` or `cargo` (a trailing `\\` continues it). ```python
blocks of the docs are run as Python snippets. In scenario headers, `--set KEY=VALUE`
fragments (with alternatives `a | b | c`) are checked as
`granflow check SCENARIO --set …`: check loads the scenario and builds the whole
simulation (every key, profile and table), without the run.

How it runs them: in order (README, docs, scenarios; fenced and four-space indented
code blocks, and inline `granflow …` spans), in one scratch directory that
holds symbolic links to the repository's scenarios/, scripts/, examples/ and docs/, so
that every output lands in the scratch directory, with `granflow` (--granflow, default
target/release/granflow) and this script's Python (as `python` and `python3`) first
on PATH, and SCRATCH, SLURM_CPUS_PER_TASK=2, SLURM_ARRAY_TASK_ID=0 set for the Slurm
example. `cargo run --release -- ARGS` is run as `granflow ARGS` (the same binary); other
`cargo run` commands get `--release --manifest-path` (the scratch directory has no
Cargo.toml, and the release profile reuses CI's release build).

What it does not run, and why (each is listed in the output):
  - synopses, i.e. commands with placeholders (RUN.h5, DIR, [--opt], …): instead each
    --option they name must appear in the command's --help, and a script they name
    must exist;
  - `cargo test` (CI runs the whole suite itself), `cargo bench` (benchmarks take tens
    of minutes and are not part of CI), `cargo install` (.ci/run installs into a
    temporary root and runs the installed binary), `sbatch` (.ci/slurm.sh runs the
    job array on a real Slurm), `python3 -m venv …` (.ci/run makes its own venv), and
    `python scripts/doc_results.py` (it reruns the tests to regenerate the docs);
  - SHORTENED below: commands whose full run would cost minutes of CI
    would be run with the extra arguments given there (e.g. --set time.t_end=…),
    with the reason.
Exit status 1 if any command fails; the output names the file and line.
"""

import argparse
import os
import pathlib
import re
import shlex
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
COMMAND_WORDS = ("granflow", "python", "python3", "cargo")
LINKS = ("scenarios", "scripts", "examples", "docs", "tests")

# regex on the command -> (extra arguments appended, reason), for commands whose full
# run would cost minutes of CI, e.g.
#   r"^granflow run scenarios/big\.toml": ("--set time.t_end=0.5", "10 min to t_end = 20 s"),
# Apart from these, every quoted command runs in full, the slowest (the 12-run
# erodible-bed sweep of the 20-layer model) in about 20 s on 2 cores.
SHORTENED = {
    r"^granflow run scenarios/hockey_channel\.toml .*domain\.cells=\[1000,1000\]": (
        "--set 'domain.cells=[100,100]'",
        "the 1000 x 1000 timing of docs/performance.md takes minutes on 2 cores"),
    r"^granflow run scenarios/(hockey|helix)_channel\.toml --output": (
        "--set time.t_end=10",
        "AvaFrame's 5 m grid to the stop takes one to two minutes of CPU"),
    r"--example flow_cost -- .*cells=\[3162,3162\]": (
        "--set 'domain.cells=[161,161]' --set time.t_end=5",
        "10^7 cells take 2.5 GB and half a minute of set-up"),
    r"--example flow_cost -- (?!.*cells=\[3162)": (
        "--set time.t_end=5",
        "a hockey-stick run to its stop takes 10 s of CPU, the full sweep a minute"),
    r"^python scripts/error_vs_runtime\.py --orders(?! --cases thacker2d)": (
        "--cases ritter,mangeney --limiters mc",
        "the whole order study (four cases, three limiters, a 5120-cell collapse) takes "
        "minutes of CPU"),
    r"^python scripts/error_vs_runtime\.py --orders --cases thacker2d,collapse2d": (
        "--limiters mc",
        "the raster cases with one limiter take 20 s of CPU, with three a minute"),
}

NOT_RUN = {
    "cargo test": "CI runs the whole test suite itself",
    "cargo bench": "benchmarks take tens of minutes; not part of CI",
    "cargo install": ".ci/run installs into a temporary root and runs the installed binary",
    "sbatch": ".ci/slurm.sh runs the job array on a real Slurm",
    "python3 -m venv": ".ci/run creates its own virtual environment the same way",
    "python scripts/doc_results.py": "it regenerates the docs' result blocks by running the "
                                     "tests (many minutes); CI runs the tests themselves",
}

PLACEHOLDER = re.compile(
    r"^(\[.*|(?!.*=\[).*\]|…|\.\.\.|\||<.*>|[A-Z][A-Z0-9_]*(\.[a-z0-9]+)?|.*=[A-Z][A-Z0-9_]*|.*….*"
    r"|my_scenario\.toml)$")


class Cmd:
    def __init__(self, source, line, text, kind="shell"):
        self.source, self.line, self.text, self.kind = source, line, text.strip(), kind

    def where(self):
        return f"{self.source.relative_to(ROOT)}:{self.line}"


def starts_with_command(s):
    return s.split(" ", 1)[0] in COMMAND_WORDS or s.startswith("cargo run")


def join_continued(lines):
    """[(line number, text)] with trailing-backslash continuations joined."""
    out, buf, start = [], "", None
    for n, l in lines:
        if start is None:
            start = n
        if l.rstrip().endswith("\\"):
            buf += l.rstrip()[:-1] + " "
            continue
        out.append((start, buf + l))
        buf, start = "", None
    return out


def from_markdown(path):
    cmds, lines = [], path.read_text().splitlines()
    fence, block, block_start = None, [], 0
    for n, l in enumerate(lines, start=1):
        m = re.match(r"^```(\w*)", l)
        if m and fence is None:
            fence, block, block_start = m.group(1), [], n
            continue
        if l.startswith("```") and fence is not None:
            if fence == "python":
                cmds.append(Cmd(path, block_start, "\n".join(t for _, t in block), "python"))
            else:
                for k, t in join_continued(block):
                    if starts_with_command(t.strip()):
                        cmds.append(Cmd(path, k, t))
            fence = None
            continue
        if fence is not None:
            block.append((n, l))
            continue
        # Indented code blocks (four spaces after a blank or indented line).
        prev_blank_or_code = n == 1 or not lines[n - 2].strip() or lines[n - 2].startswith("    ")
        if l.startswith("    ") and prev_blank_or_code and starts_with_command(l.strip()):
            cmds.append(Cmd(path, n, l))
            continue
        for span in re.findall(r"`([^`]+)`", l):
            if is_inline_command(span):
                cmds.append(Cmd(path, n, span))
    return cmds


def is_inline_command(span):
    """An inline span is a command, not a mention such as `granflow run` or
    `granflow run --set`, when it has an argument beyond the subcommand."""
    toks = span.split()
    if not toks:
        return False
    return (starts_with_command(span) and len(toks) >= 3 and not toks[-1].startswith("--")
            or toks[0] in ("python", "python3") and len(toks) >= 2)


def from_toml_header(path):
    cmds = []
    header = []
    for n, l in enumerate(path.read_text().splitlines(), start=1):
        if not l.startswith("#"):
            break
        header.append((n, l[1:].strip()))
    for n, t in join_continued(header):
        if starts_with_command(t):
            cmds.append(Cmd(path, n, t))
            continue
        for span in re.findall(r"`([^`]+)`", t):
            if is_inline_command(span):
                cmds.append(Cmd(path, n, span))
        if "--set" in t and not path.parent.name == "sweeps":
            for sets in set_fragments(t[t.index("--set"):]):
                rel = path.relative_to(ROOT)
                cmds.append(Cmd(path, n, "granflow check " + shlex.quote(str(rel)) + " "
                                + " ".join("--set " + shlex.quote(s) for s in sets), "fragment"))
    return cmds


def set_fragments(text):
    """`--set a=1 | 2 --set b=3` -> [["a=1", "b=3"], ["a=2", "b=3"]]."""
    try:
        toks = shlex.split(text)
    except ValueError:
        toks = text.split()
    groups, i = [], 0
    while i + 1 < len(toks) and toks[i] == "--set":
        key, _, value = toks[i + 1].partition("=")
        alts = [prose_trimmed(value)]
        i += 2
        while i + 1 < len(toks) and toks[i] == "|":
            alts.append(prose_trimmed(toks[i + 1]))
            i += 2
        groups.append([f"{key}={v}" for v in alts])
    runs = [[]]
    for g in groups:
        runs = [r + [a] for r in runs for a in g] if len(g) > 1 else [r + g for r in runs]
    return [r for r in runs if r]


def prose_trimmed(value):
    """A value at the end of a sentence: `1e-10).` -> `1e-10` (only unbalanced
    parentheses and final punctuation are removed)."""
    value = value.rstrip(".,;")
    while value.endswith(")") and value.count(")") > value.count("("):
        value = value[:-1].rstrip(".,;")
    return value


def collect():
    cmds = from_markdown(ROOT / "README.md")
    for p in sorted((ROOT / "docs").glob("*.md")):
        cmds += from_markdown(p)
    for p in sorted((ROOT / "scenarios").glob("*.toml")) + sorted(
            (ROOT / "scenarios/sweeps").glob("*.toml")):
        cmds += from_toml_header(p)
    return cmds


def classify(cmd):
    """('run', text) | ('synopsis', tokens) | ('skip', reason)."""
    if cmd.kind == "python":
        return "run", cmd.text
    text = re.sub(r"^cargo run --release -- ", "granflow ", cmd.text)
    # The scratch directory has no Cargo.toml; release reuses CI's release build.
    if text.startswith("cargo run "):
        # Any other `cargo run` (an example, say), with or without --release.
        rest = re.sub(r"^cargo run (--release )?", "", text)
        text = f"cargo run --release --manifest-path {ROOT}/Cargo.toml {rest}"
    for prefix, why in NOT_RUN.items():
        if text.startswith(prefix) or f" {prefix} " in f" {text} ":
            return "skip", why
    try:
        toks = shlex.split(text, comments=True)
    except ValueError:
        return "synopsis", text.split()
    if any(PLACEHOLDER.match(t) for t in toks[1:]):
        return "synopsis", toks
    return "run", text


def check_synopsis(toks, env, cwd):
    """Every --option of a synopsis is in the command's --help; a script exists."""
    if toks[0] in ("python", "python3"):
        script = ROOT / toks[1]
        if not script.is_file():
            return False, f"no such script {toks[1]}"
        flags = [t.split("=")[0].strip("[]") for t in toks[2:] if t.lstrip("[").startswith("--")]
        if not flags:
            return True, "script exists"
        help_cmd = [toks[0], str(script), "--help"]
    elif toks[0] == "granflow":
        subs = [t for t in toks[1:3] if re.fullmatch(r"[a-z]+", t)]
        flags = [t.split("=")[0].strip("[]") for t in toks if t.lstrip("[").startswith("--")]
        help_cmd = ["granflow", *subs, "--help"]
    else:
        return True, "not checked"
    p = subprocess.run(help_cmd, capture_output=True, text=True, env=env, cwd=cwd)
    missing = [f for f in flags if f not in p.stdout]
    if p.returncode != 0 or missing:
        return False, f"`{' '.join(help_cmd)}` exit {p.returncode}, options not in it: {missing}"
    return True, f"options {' '.join(flags) or '(none)'} in --help"


def check_test_filter(text, tests, slow=()):
    """A quoted `cargo test [--test main] FILTER [-- --exact]` selects at least one test,
    and says --include-ignored (or --ignored) if it selects one of the slow tier (the
    tests marked `#[ignore = "slow: …"]`, which `cargo test` alone skips)."""
    toks = shlex.split(text)
    before, _, after = " ".join(toks).partition(" -- ")
    words = before.split()[2:]
    filters, skip_next = [], False
    for w in words:
        if skip_next:
            skip_next = False
        elif w in ("--test", "--features", "-p", "--package", "--lib", "--bin"):
            skip_next = w not in ("--lib",)
        elif not w.startswith("-"):
            filters.append(w)
    flags = after.split()
    exact = "--exact" in flags
    selects = (lambda t: any((t == f) if exact else (f in t) for f in filters)) if filters \
        else (lambda t: True)
    for f in filters:
        if not any((t == f) if exact else (f in t) for t in tests):
            return False, f"no test {'named' if exact else 'matching'} {f!r} in the test crate"
    chosen_slow = [t for t in slow if selects(t)]
    if filters and chosen_slow and not {"--include-ignored", "--ignored"} & set(flags):
        return False, (f"selects {len(chosen_slow)} slow-tier test(s) ({chosen_slow[0]}, …) "
                       "that only run with `-- --include-ignored`")
    return True, "tests exist" if filters else "whole target"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--granflow", default=str(ROOT / "target/release/granflow"))
    ap.add_argument("--list", action="store_true", help="list the commands, run nothing")
    ap.add_argument("--keep", help="scratch directory to use and keep (default: a temp dir)")
    ap.add_argument("--test-list", help="output of `cargo test --test main -- --list`: every "
                    "quoted `cargo test` must then name tests that exist")
    ap.add_argument("--slow-list", help="output of `cargo test --test main -- --list "
                    "--ignored` (the slow tier): a quoted `cargo test` that selects one must "
                    "say --include-ignored")
    args = ap.parse_args()
    tests, slow = None, []

    def names(path):
        return [l.split(": test")[0] for l in pathlib.Path(path).read_text().splitlines()
                if l.endswith(": test")]

    if args.slow_list:
        slow = names(args.slow_list)
    if args.test_list:
        tests = names(args.test_list)
        # Inline `cargo test …` spans anywhere in the docs, even mid-sentence and
        # broken across lines, must name tests that exist.
        bad = 0
        for md in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
            text = md.read_text()
            for m in re.finditer(r"`(cargo test[^`]*)`", text):
                cmd = " ".join(m.group(1).replace("//!", " ").split())
                ok, why = check_test_filter(cmd, tests, slow)
                if not ok:
                    line = text.count("\n", 0, m.start()) + 1
                    print(f"FAIL      {md.relative_to(ROOT)}:{line}: {cmd}  ({why})")
                    bad += 1
    cmds = collect()
    if tests is not None:
        # And those of the code blocks and scenario headers.
        for c in cmds:
            if c.text.startswith("cargo test"):
                ok, why = check_test_filter(c.text, tests, slow)
                if not ok:
                    print(f"FAIL      {c.where()}: {c.text}  ({why})")
                    bad += 1
        if bad:
            return 1
    if args.list:
        for c in cmds:
            kind, what = classify(c)
            print(f"{c.where():45} {kind:9} {c.text if kind != 'skip' else what}")
        return 0

    work = pathlib.Path(args.keep or tempfile.mkdtemp(prefix="granflow-doc-"))
    work.mkdir(parents=True, exist_ok=True)
    for name in LINKS:
        if not (work / name).exists():
            (work / name).symlink_to(ROOT / name)
    bin_dir = work / ".bin"
    bin_dir.mkdir(exist_ok=True)
    # Wrappers, not links: a link to a venv's python would lose the venv.
    for name, target in (("granflow", pathlib.Path(args.granflow).resolve()),
                         ("python", pathlib.Path(sys.executable)),
                         ("python3", pathlib.Path(sys.executable))):
        wrapper = bin_dir / name
        wrapper.write_text(f'#!/bin/sh\nexec "{target}" "$@"\n')
        wrapper.chmod(0o755)
    env = dict(os.environ, PATH=f"{bin_dir}:{os.environ['PATH']}", SCRATCH=str(work / "scratch"),
               SLURM_CPUS_PER_TASK="2", SLURM_ARRAY_TASK_ID="0", MPLBACKEND="Agg")

    failures, counts, t0 = [], {"run": 0, "synopsis": 0, "skip": 0}, time.time()
    for c in cmds:
        kind, what = classify(c)
        counts[kind] += 1
        if kind == "skip":
            print(f"skip      {c.where()}: {c.text}  ({what})")
            continue
        if kind == "synopsis":
            ok, why = check_synopsis(what, env, work)
            print(f"{'synopsis' if ok else 'FAIL':9} {c.where()}: {c.text}  ({why})")
            if not ok:
                failures.append((c, why))
            continue
        note = ""
        if c.kind == "python":
            argv = [sys.executable, "-c", what]
        else:
            for pattern, (extra, why) in SHORTENED.items():
                if re.search(pattern, what):
                    what, note = f"{what} {extra}", f" [shortened: {extra}: {why}]"
            argv = ["bash", "-c", what]
        start = time.time()
        try:
            p = subprocess.run(argv, cwd=work, env=env, capture_output=True, text=True,
                               timeout=600)
            code, err = p.returncode, (p.stderr or p.stdout)[-2000:]
        except subprocess.TimeoutExpired:
            code, err = "timeout", "took more than 600 s"
        shown = "python snippet" if c.kind == "python" else c.text
        if code == 0:
            print(f"ok        {c.where()}: {shown}  ({time.time() - start:.1f} s){note}")
        else:
            print(f"FAIL      {c.where()}: {shown}  (exit {code}){note}\n{err}")
            failures.append((c, f"exit {code}"))
    print(f"\n{counts['run']} commands run, {counts['synopsis']} synopses checked against "
          f"--help, {counts['skip']} not run (reasons above), {len(failures)} failed, "
          f"{time.time() - t0:.0f} s; scratch directory {work}")
    for c, why in failures:
        print(f"  FAILED {c.where()}: {c.text}  ({why})")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
