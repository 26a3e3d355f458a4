"""Conformance and fault suite: classes of misuse and bad input over the five FMUs
(RigidRockingBlock, FlexibleRockingOscillator, PostTensionedRockingBlock, GroundMotionSource,
LinearBuildingStorey), driving every
FMI 2.0 co-simulation function through fmpy's low-level ``FMU2Slave``.

The cases live in tests/fault_harness.py (a case = a small function or a row of a table). Each runs in a
process of its own -- forked by a harness server that imported fmpy and numpy once -- with a timeout, so a
crash or a hang is a failed case, never a dead pytest. The cases
selected for the session run up front on all cores (``FAULT_SUITE_JOBS``, default: the CPU count, at most 4);
each test then asserts on its case's JSON record:

1. the process survived (exit code 0, no signal) and finished within the case's timeout;
2. the statuses are exactly those of FMI 2.0 (the project's own binary): fmi2Error for an invalid
   argument, value or call sequence (the instance then in the error state), fmi2Discard for a step the
   simulator refuses, fmi2OK otherwise;
3. the logged message names the variable or the call, with logging on or off;
4. every variable is bit-identical after a refused call; after fmi2Error, fmi2SetFMUstate of a state saved
   before brings the instance back bit-identical (the bytes of fmi2SerializeFMUstate), and it steps on
   exactly like a control instance that never saw the call.

Checks of kinds 2-4 are recorded by the worker as it goes; a case declares which kinds it must contain.
The summary line (classes tried / passing, the longest case, the longest single FMI call) is printed at the
end of the session. Run one case by hand: ``python tests/fault_harness.py --case <id> --config <json>``
(the config file is written into the session's temporary folder).
"""
from __future__ import annotations

import json
import os
from contextlib import nullcontext as _nullcontext
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
import fault_harness as fh  # noqa: E402

sys.path.remove(str(HERE))

MIN_CLASSES = 100
JOBS = int(os.environ.get("FAULT_SUITE_JOBS", "0")) or max(2, min(4, os.cpu_count() or 2))


# ---------------------------------------------------------------------------------------------- running
def _write_config(dest: Path, paths: list) -> Path:
    from fmpy import extract

    fmus = {p.stem: {"path": str(p), "unzip": str(extract(str(p), unzipdir=str(dest / f"{p.stem}_unzipped")))}
            for p in paths}
    config = dest / "fmus.json"
    config.write_text(json.dumps({"fmus": fmus}))
    return config


@pytest.fixture(scope="session")
def fault_configs(request, built_fmus, build_module, tmp_path_factory):
    """{kind: config file} of the session's FMUs, each extracted once (the cases share the read-only
    folders): "pythonfmu" the four pythonfmu FMUs; "standalone" the self-contained rocking FMUs (the source
    and the storey, which exist as pythonfmu FMUs only, stay those) -- built only when a standalone case is
    selected; a failed build leaves the kind out (its cases skip with the build's error)."""
    kinds = {kind for kind, _ in _selected_cases(request.session)} or set(fh.KINDS)
    configs = {}
    if "pythonfmu" in kinds:
        configs["pythonfmu"] = _write_config(tmp_path_factory.mktemp("fault_fmus"),
                                             [built_fmus[name] for name in fh.FMUS])
    if "standalone" in kinds:
        try:
            sa = fh.standalone_fmus(build_module, tmp_path_factory)
        except Exception as exc:
            configs["standalone"] = exc
        else:
            configs["standalone"] = _write_config(tmp_path_factory.mktemp("fault_fmus_standalone"),
                                                  [sa.get(name, built_fmus[name]) for name in fh.FMUS])
    return configs


class _Server:
    """A harness fork server (tests/fault_harness.py --serve) fed one request per line."""

    def __init__(self, pycache: Path):
        env = {**os.environ, "FAULT_SUITE_PYCACHE": str(pycache)}
        self.proc = subprocess.Popen([sys.executable, str(HERE / "fault_harness.py"), "--serve"], cwd=str(ROOT),
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1, env=env)

    def run(self, request: dict) -> dict:
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError("the harness server died")
        return json.loads(line)

    def close(self):
        try:
            self.proc.stdin.close()
            self.proc.wait(timeout=10)
        except Exception:
            self.proc.kill()


def _run_plain(request: dict) -> dict:
    """Fallback without the fork server (FAULT_SUITE_NO_FORK=1): one fresh interpreter per case."""
    t0 = time.perf_counter()
    cwd = Path(request["cwd"])
    try:
        with open(cwd / "stdout.txt", "w") as out, open(cwd / "stderr.txt", "w") as err:
            proc = subprocess.run([sys.executable, str(HERE / "fault_harness.py"), "--case", request["case"],
                                   "--config", request["config"], "--out", request["out"]], cwd=str(cwd),
                                  stdout=out, stderr=err, timeout=request["timeout"])
        rc, sig = (proc.returncode, None) if proc.returncode >= 0 else (None, -proc.returncode)
        return {"case": request["case"], "rc": rc, "signal": sig, "timed_out": False,
                "elapsed": time.perf_counter() - t0}
    except subprocess.TimeoutExpired:
        return {"case": request["case"], "rc": None, "signal": None, "timed_out": True,
                "elapsed": time.perf_counter() - t0}


def _selected_cases(session) -> list:
    """The (kind, case id) pairs of the session's selected test_fault_case items."""
    pairs = []
    for item in session.items:
        callspec = getattr(item, "callspec", None)
        if callspec is not None and "cid" in callspec.params and item.module.__name__ == __name__:
            pairs.append((callspec.params["kind"], callspec.params["cid"]))
    return pairs


def _all_pairs() -> list:
    return [(kind, cid) for kind in fh.KINDS for cid in fh.CASES if fh.not_applicable(kind, cid) is None]


@pytest.fixture(scope="session")
def fault_records(request, fault_configs, tmp_path_factory):
    """Run every selected case on every selected kind of FMU (in parallel: JOBS fork servers) and return
    {(kind, case id): outcome}."""
    pairs = [(k, c) for k, c in (_selected_cases(request.session) or _all_pairs())
             if isinstance(fault_configs.get(k), Path) and fh.not_applicable(k, c) is None]
    base = tmp_path_factory.mktemp("fault_cases")
    todo: "queue.Queue[tuple]" = queue.Queue()
    for pair in sorted(pairs, key=lambda kc: -fh.CASES[kc[1]].timeout):
        todo.put(pair)
    results: dict = {}
    no_fork = os.environ.get("FAULT_SUITE_NO_FORK") == "1"
    t_start = time.perf_counter()

    def worker():
        server = None if no_fork else _Server(base / "pycache")
        try:
            while True:
                try:
                    kind, cid = todo.get_nowait()
                except queue.Empty:
                    return
                cwd = base / kind / cid.replace("/", "__")
                cwd.mkdir(parents=True)
                req = {"case": cid, "config": str(fault_configs[kind]), "out": str(cwd / "record.json"),
                       "cwd": str(cwd), "timeout": fh.CASES[cid].timeout}
                try:
                    outcome = _run_plain(req) if server is None else server.run(req)
                except Exception as exc:  # the server itself died: report it, start another one
                    outcome = {"case": cid, "rc": None, "signal": None, "timed_out": False, "elapsed": 0.0,
                               "server_error": repr(exc)}
                    server.close()
                    server = _Server(base / "pycache")
                rec_path = cwd / "record.json"
                outcome["record"] = json.loads(rec_path.read_text()) if rec_path.exists() else None
                outcome["stderr"] = (cwd / "stderr.txt").read_text(errors="replace")[-3000:] \
                    if (cwd / "stderr.txt").exists() else ""
                outcome["cwd"] = str(cwd)
                results[(kind, cid)] = outcome
        finally:
            if server is not None:
                server.close()

    threads = [threading.Thread(target=worker, daemon=True) for _ in range(JOBS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    wall = time.perf_counter() - t_start
    yield results
    _summary(request.config, results, wall)


def _verdict(cid: str, outcome: dict) -> list:
    """The list of failures of one case (empty: the case passes)."""
    case = fh.CASES[cid]
    problems = []
    if outcome.get("server_error"):
        problems.append(f"harness server error: {outcome['server_error']}")
    if outcome["timed_out"]:
        problems.append(f"did not finish within {case.timeout:g} s (a hang)")
    elif outcome["signal"] is not None:
        problems.append(f"the process died with signal {outcome['signal']} (a crash)")
    elif outcome["rc"] != 0:
        problems.append(f"the process exited with code {outcome['rc']}")
    rec = outcome.get("record")
    if rec is None:
        problems.append("no record written" + (f"; stderr: {outcome['stderr'][-1500:]}" if outcome["stderr"] else ""))
        return problems
    if rec.get("error"):
        problems.append(f"the case raised:\n{rec['error']}")
    if rec.get("pwned"):
        problems.append("the file 'pwned' exists: code from a state was executed")
    checks = rec.get("checks") or []
    for kind in case.kinds:
        if not any(c["kind"] == kind for c in checks):
            problems.append(f"no check of kind {kind!r} was reached")
    for c in checks:
        if not c["ok"]:
            problems.append(f"[{c['kind']}] {c['label']}: {json.dumps(c['detail'], default=repr)[:1500]}")
    return problems


def _kind_summary(kind: str, results: dict, verdicts: dict) -> list:
    """The summary lines of one kind of FMU: classes tried / passing, the longest case and FMI call."""
    tried = len(results)
    passing = sum(1 for v in verdicts.values() if not v)
    xfail = [cid for cid in results if fh.CASES[cid].xfail or fh.standalone_xfail(kind, cid)]
    xfail_failing = sum(1 for cid in xfail if verdicts[cid])
    na = sum(1 for cid in fh.CASES if fh.not_applicable(kind, cid) is not None)
    longest = max(results.items(), key=lambda kv: kv[1]["elapsed"], default=(None, {"elapsed": 0.0}))

    def slowest(key):
        return max(((c.get("elapsed", 0.0), cid, c) for cid, o in results.items()
                    for c in [((o.get("record") or {}).get(key) or {})]), default=(0.0, None, {}))

    slow_call, slow_step = slowest("max_call"), slowest("max_step")
    families: dict = {}
    for cid, v in verdicts.items():
        fam = fh.CASES[cid].family
        t, p = families.get(fam, (0, 0))
        families[fam] = (t + 1, p + (not v))
    return [f"{kind} FMUs: {tried} classes tried, {passing} passing ({len(xfail)} strict xfails, "
            f"{xfail_failing} of them failing as expected; {na} not applicable to this kind)",
            f"  longest case: {longest[0]} {longest[1]['elapsed']:.2f} s; longest FMI call: "
            f"{slow_call[2].get('call')} {slow_call[0]:.3f} s in {slow_call[1]}; longest fmi2DoStep: "
            f"{slow_step[0]:.3f} s in {slow_step[1]}",
            "  by family: " + ", ".join(f"{f} {p}/{t}" for f, (t, p) in sorted(families.items()))]


def _summary(config, results: dict, wall: float) -> None:
    lines = [f"fault suite: cases wall time {wall:.1f} s on {JOBS} processes (both kinds of FMU)"]
    verdicts = {key: _verdict(key[1], o) for key, o in results.items()}
    for kind in fh.KINDS:
        mine = {cid: o for (k, cid), o in results.items() if k == kind}
        if not mine:
            continue
        lines += _kind_summary(kind, mine, {cid: verdicts[(kind, cid)] for cid in mine})
    out_dir = os.environ.get("FAULT_SUITE_REPORT")
    if out_dir:
        report = {f"{kind}:{cid}": {"problems": v, "elapsed": results[(kind, cid)]["elapsed"],
                                    "figures": (results[(kind, cid)].get("record") or {}).get("figures"),
                                    "what": fh.CASES[cid].what}
                  for (kind, cid), v in verdicts.items()}
        Path(out_dir).write_text(json.dumps(report, indent=1, default=repr))
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    capture = config.pluginmanager.get_plugin("capturemanager")
    with capture.global_and_fixture_disabled() if capture is not None else _nullcontext():
        if reporter is not None:
            reporter.write("\n")  # after the progress dots
        for line in lines:
            if reporter is not None:
                reporter.write_line(line)
            else:  # pragma: no cover
                print(line)


# ---------------------------------------------------------------------------------------------- tests
def _params():
    """(kind, case id) for every case on both kinds of FMU; the pythonfmu ids are the case ids, the
    standalone ids "standalone:<case id>"; a case that does not apply to a kind is a skip with the reason."""
    out = []
    for kind in fh.KINDS:
        for cid, case in fh.CASES.items():
            xfail = case.xfail or fh.standalone_xfail(kind, cid)
            marks = [pytest.mark.xfail(strict=True, reason=xfail)] if xfail else []
            reason = fh.not_applicable(kind, cid)
            if reason is not None:
                marks = [pytest.mark.skip(reason=f"not applicable to the {kind} FMUs: {reason}")]
            out.append(pytest.param(kind, cid, id=cid if kind == "pythonfmu" else f"{kind}:{cid}", marks=marks))
    return out


def test_at_least_100_classes():
    assert len(fh.CASES) >= MIN_CLASSES
    undescribed = [c.cid for c in fh.CASES.values() if not c.what]
    assert not undescribed, undescribed
    covered = {fmu for c in fh.CASES.values() for fmu in fh.FMUS if fh.SHORT[fmu] in c.cid.split("/")[1:2]}
    assert covered == set(fh.FMUS)  # the rocking FMUs and the two system FMUs


def test_robustness_page_is_what_the_case_list_generates():
    """docs/robustness.md is generated from the case list (one row per class: its cases, FMUs, statuses and
    what holds), so that it cannot drift from the suite; every class has its description and no description
    is left without a class."""
    assert set(fh.FAMILIES) == {case.family for case in fh.CASES.values()}
    page = (ROOT / "docs" / "robustness.md").read_text(encoding="utf-8")
    assert page == fh.robustness_page(), ("docs/robustness.md is not what the case list generates: run "
                                          "python tests/fault_harness.py --write-doc docs/robustness.md")


@pytest.mark.parametrize("kind, cid", _params())
def test_fault_case(fault_configs, fault_records, kind, cid):
    if isinstance(fault_configs[kind], Exception):
        pytest.skip(f"the {kind} FMUs could not be built: {fault_configs[kind]!r}")
    problems = _verdict(cid, fault_records[(kind, cid)])
    assert not problems, f"{kind}: {cid} ({fh.CASES[cid].what}):\n  " + "\n  ".join(problems)
