"""The FMUs under the reference checkers: the FMU Compliance Checker (modelica-tools
FMUComplianceChecker, `fmuCheck.linux64`, built with FMI Library) and Reference-FMUs' `fmusim` (tag v0.0.39)
run every FMU the project builds (the pythonfmu FMUs and the self-contained ones) on its cross-check scene
(rocking_model/fmi/build.py: CROSS_CHECK, the input table sampled at the communication points); each must run
with no error or warning, and its outputs must equal fmpy's run of the same scene.

    python tests/reference_checkers.py [--fmus DIR] [--out DIR]

finds the checkers on PATH or through $FMUCHECK / $FMUSIM, builds the FMUs into a temporary folder unless
--fmus names a build_fmu.py output folder (DIR/*.fmu, DIR/standalone/*.fmu), prints one line per FMU and
checker, and exits 1 on any finding. Neither checker is downloaded or built here; how to build them offline:
docs/reference-checkers.md.
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TOOLS = {"fmuCheck": ("FMUCHECK", "fmuCheck.linux64"), "fmusim": ("FMUSIM", "fmusim")}
#: outputs equal to fmpy's: both run the same binary with the same inputs at the same points; they may differ
#: only in how an input is interpolated at a communication point (a rounding of t)
RTOL, ATOL = 1e-9, 1e-12
HOWTO = "see docs/reference-checkers.md to build them offline, then put them on PATH or set $FMUCHECK / $FMUSIM"


def find_tool(name: str) -> str | None:
    env, exe = TOOLS[name]
    path = os.environ.get(env) or shutil.which(exe)
    return path if path and os.path.isfile(path) and os.access(path, os.X_OK) else None


def _read_csv(path: Path) -> dict:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    names = [n.strip().strip('"') for n in rows[0]]
    cols = {n: [] for n in names}
    for row in rows[1:]:
        if not row:
            continue
        for n, x in zip(names, row):
            x = x.strip()
            cols[n].append(1.0 if x == "true" else 0.0 if x == "false" else float(x))
    return cols


def _compare(name: str, tool: str, got: dict, ref, rows: int | None = None) -> list:
    """Findings of a checker's result against fmpy's (a structured array; its first `rows` rows)."""
    problems = []
    ref = ref[:rows] if rows is not None else ref
    t_ref = list(ref["time"])
    t_got = got.get("time", [])
    if len(t_got) != len(t_ref) or any(not math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-12)
                                       for a, b in zip(t_got, t_ref)):
        return [f"{tool}: {len(t_got)} rows (time {t_got[:1]}..{t_got[-1:]}), fmpy {len(t_ref)}"]
    for col in ref.dtype.names[1:]:
        if col not in got:
            problems.append(f"{tool}: no column {col}")
            continue
        worst = max(abs(float(a) - float(b)) for a, b in zip(got[col], ref[col]))
        scale = max(abs(float(b)) for b in ref[col]) or 1.0
        if worst > ATOL + RTOL * scale:
            problems.append(f"{tool}: {col} differs from fmpy's by {worst:.3g} (scale {scale:.3g})")
    return problems


def check(fmu: Path, tools: dict, work: Path) -> list:
    """Run the checkers on one FMU; return [(tool, summary, [findings])]."""
    from rocking_model.fmi import build

    name = fmu.stem
    spec = build.CROSS_CHECK[name]
    opts = {"StartTime": 0.0, "StopTime": spec["stop"], "StepSize": spec["step"], "RelTol": spec["rel_tol"]}
    table = build.cross_check_input(name)
    ref = build.simulate_cross_check(fmu, table, opts, [])
    kind = fmu.parent.name if fmu.parent.name == "standalone" else "pythonfmu"
    out = work / f"{kind}_{name}"
    out.mkdir(parents=True, exist_ok=True)
    inp = None
    if table is not None:
        inp = out / "in.csv"
        build.write_cross_check_csv(inp, table)
    report = []
    if "fmuCheck" in tools:
        res = out / "fmuCheck.csv"
        cmd = [tools["fmuCheck"], "-k", "cs", "-l", "3", "-s", repr(spec["stop"]), "-h", repr(spec["step"]),
               "-o", str(res), "-t", str(out / "fmuCheck_tmp")]
        if inp is not None:
            cmd += ["-i", str(inp)]
        (out / "fmuCheck_tmp").mkdir(exist_ok=True)
        proc = subprocess.run([*cmd, str(fmu)], capture_output=True, text=True)
        text = proc.stdout + proc.stderr
        (out / "fmuCheck.log").write_text(text)
        m_w = re.search(r"(\d+) Warning\(s\)", text)
        m_e = re.search(r"(\d+) Error\(s\)", text)
        findings = [f"fmuCheck: {line.strip()}" for line in text.splitlines()
                    if re.search(r"\[(WARNING|ERROR|FATAL)\]", line)]
        if proc.returncode != 0 or not m_w or not m_e or int(m_w.group(1)) or int(m_e.group(1)):
            findings.append(f"fmuCheck: exit code {proc.returncode}, "
                            f"{m_w.group(0) if m_w else '? warnings'}, {m_e.group(0) if m_e else '? errors'}")
        if res.exists():
            findings += _compare(name, "fmuCheck", _read_csv(res), ref)
        report.append(("fmuCheck", f"{m_w.group(0) if m_w else '?'}, {m_e.group(0) if m_e else '?'}", findings))
    if "fmusim" in tools:
        res = out / "fmusim.csv"
        cmd = [tools["fmusim"], "--interface-type", "cs", "--stop-time", repr(spec["stop"]),
               "--output-interval", repr(spec["step"]), "--output-file", str(res), "--log-fmi-calls"]
        if inp is not None:
            cmd += ["--input-file", str(inp)]
        proc = subprocess.run([*cmd, str(fmu)], capture_output=True, text=True)
        text = proc.stdout + proc.stderr
        (out / "fmusim.log").write_text(text)
        # with --log-fmi-calls each call is logged with its status: any but OK is a finding
        bad = [line.strip() for line in text.splitlines()
               if re.search(r"->\s*(fmi2Warning|fmi2Discard|fmi2Error|fmi2Fatal|[1-4])\b", line)
               or re.match(r"\s*\[?(WARNING|ERROR|FATAL)", line, re.I)]
        # fmusim v0.0.39 ends a co-simulation at the first fmi2DoStep status above fmi2OK (FMI2CSSimulation.c:
        # CALL(doStepStatus), `status > FMIOK` -> TERMINATE, exit code 1), fmi2Warning included: every FMU must
        # run its whole scene with every call OK (the overturning of a scene is an event, logged with fmi2OK
        # under logEvents, not a warning) and fmusim must exit with 0
        findings = [f"fmusim: {line}" for line in bad[:10]]
        if proc.returncode != 0:
            findings.append(f"fmusim: exit code {proc.returncode}: {text.strip()[-500:]}")
        if res.exists():
            findings += _compare(name, "fmusim", _read_csv(res), ref)
        elif proc.returncode == 0:
            findings.append("fmusim: no result file")
        lines = text.splitlines()
        calls = sum(1 for line in lines if line.startswith("fmi2"))
        report.append(("fmusim", f"exit {proc.returncode}, {calls} FMI calls logged, {len(bad)} not OK", findings))
    return report


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fmus", help="a build_fmu.py output folder (default: build the FMUs into a temporary one)")
    p.add_argument("--out", help="keep the checkers' logs and results here")
    args = p.parse_args(argv)
    tools = {n: t for n in TOOLS if (t := find_tool(n))}
    if not tools:
        print(f"reference_checkers: neither fmuCheck.linux64 nor fmusim found; {HOWTO}", file=sys.stderr)
        return 2
    sys.path.insert(0, str(ROOT))
    from rocking_model.fmi import build

    with tempfile.TemporaryDirectory(prefix="rocking_checkers_") as tmp:
        folder = Path(args.fmus) if args.fmus else Path(tmp) / "fmus"
        if not args.fmus:
            build.build_all(folder)
            build.build_standalone(folder)
        fmus = sorted(folder.glob("*.fmu")) + sorted((folder / "standalone").glob("*.fmu"))
        work = Path(args.out) if args.out else Path(tmp) / "runs"
        failed = 0
        for fmu in fmus:
            kind = "standalone" if fmu.parent.name == "standalone" else "pythonfmu"
            for tool, summary, findings in check(fmu, tools, work):
                status = "OK" if not findings else "FAILED"
                print(f"{tool:9s} {kind:10s} {fmu.stem:26s} {status}: {summary}"
                      + ("; outputs equal fmpy's" if not findings else ""))
                for f in findings:
                    print(f"    {f}")
                failed += bool(findings)
        missing = [TOOLS[n][1] for n in TOOLS if n not in tools]
        if missing:
            print(f"reference_checkers: not run: {', '.join(missing)} ({HOWTO})")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
