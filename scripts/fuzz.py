"""Coverage-guided fuzzing of rtta's own parsers with atheris (libFuzzer), one target at a
time, in a subprocess (issue 42; the targets are in tests/fuzz_targets.py).

    python scripts/fuzz.py TARGET [--seconds N] [--work DIR]    run TARGET for N seconds (60)
    python scripts/fuzz.py --corpus [TARGET]                    (re)write tests/fuzz_corpus/[TARGET]
    python scripts/fuzz.py --list                               the targets

The contract: an input gives a result or an RttaError; any other exception, more than 2 s
(libFuzzer's -timeout) or more than 2048 MB resident (-rss_limit_mb) is a finding, saved as
DIR/crash-*, timeout-* or oom-* (DIR: /tmp/rtta-fuzz/TARGET, whose corpus/ keeps what the run
found, beside the seeds of tests/fuzz_corpus/TARGET). Prints the executions, coverage and
findings; exits 1 when there are findings. Run one at a time, niced, on a shared machine.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import re
import subprocess
import sys
import time
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1] / "tests"
sys.path.insert(0, str(TESTS))
os.environ.setdefault("RTTA_MEMORY_LIMIT_MB", "512")  # fuzz_targets.LOADER_LIMIT_MB: the loader's limits bite early


def main() -> int:
    if len(sys.argv) > 2 and sys.argv[1] == "--worker":
        return _worker(sys.argv[2], sys.argv[3:])
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("target", nargs="?")
    parser.add_argument("--seconds", type=int, default=60)
    parser.add_argument("--work", type=Path, default=None)
    parser.add_argument("--corpus", action="store_true", help="(re)write the seed corpora (of TARGET, or all)")
    parser.add_argument("--list", action="store_true")
    args = parser.parse_args()
    import fuzz_targets

    if args.list:
        print("\n".join(fuzz_targets.TARGETS))
        return 0
    if args.corpus:
        from fuzz_corpus_make import write_corpus

        for target, count in write_corpus(fuzz_targets.CORPUS, [args.target] if args.target else None).items():
            print(f"{target}: {count} seeds")
        return 0
    if args.target not in fuzz_targets.TARGETS:
        parser.error(f"TARGET must be one of {', '.join(fuzz_targets.TARGETS)}")
    return _run(args.target, args.seconds, args.work or Path("/tmp/rtta-fuzz") / args.target)


# Targets whose worker is restarted from the corpus every so many executions: ifcopenshell
# keeps about 5 KB of every file and entity made (a loop of 20,000 files and removed entities
# alone grew 93 MB), which over a million executions reached -rss_limit_mb with no input at
# fault (the "oom" of 2026-11-27, 18 bytes that take 78 MB alone).
RESTART_EVERY = {"ifc": 150_000}


def _run(target: str, seconds: int, work: Path) -> int:
    """Fuzz until `seconds` have passed. libFuzzer stops at its first finding: a timeout that
    does not come back when its input is run again alone (a loaded machine, a first import)
    is set aside in DIR/unconfirmed/ and the fuzzing goes on from the corpus found so far;
    any other finding ends the run."""
    import fuzz_targets

    found, unconfirmed = work / "corpus", work / "unconfirmed"
    found.mkdir(parents=True, exist_ok=True)
    unconfirmed.mkdir(exist_ok=True)
    start, runs, cov, findings, logs = time.monotonic(), 0, ("?", "?"), [], []
    while not findings and (left := int(seconds - (time.monotonic() - start))) >= 5:
        before = {p.name for p in work.iterdir()}
        log = _libfuzzer(target, found, work, left, RESTART_EVERY.get(target))
        logs.append(log)
        if "stat::number_of_executed_units" not in log:  # the worker never fuzzed: say why, stop
            print(f"{target}: the fuzzing worker failed to start:\n{log[-3000:]}", flush=True)
            return 2
        runs += sum(int(n) for n in re.findall(r"stat::number_of_executed_units:\s*(\d+)", log)[-1:])
        cov = (re.findall(r"cov: (\d+) ft: (\d+)", log) or [cov])[-1]
        for name in sorted(p.name for p in work.iterdir() if p.name not in before):
            if not re.match(r"(crash|timeout|oom|slow)", name):
                continue
            took = _replay(target, work / name) if name.startswith(("timeout", "slow", "oom")) else None
            if took is not None and took[0] < fuzz_targets.LIMIT_S and took[1] < fuzz_targets.MEMORY_MB:
                (work / name).rename(unconfirmed / name)
                alone = f"{took[0]:.2f} s, {took[1]:.0f} MB alone"
                print(f"{target}: {name} not reproduced ({alone}): set aside, fuzzing on", flush=True)
            else:
                findings.append(name)
    (work / "last.log").write_text("\n".join(logs))
    elapsed = time.monotonic() - start
    print(
        f"{target}: {runs:,} executions in {elapsed:.0f} s, coverage {cov[0]} edges / {cov[1]} features, "
        f"corpus {len(list(found.iterdir()))} found + {len(fuzz_targets.seeds(target))} seeds, "
        f"unconfirmed timeouts {len(list(unconfirmed.iterdir()))}, findings: {', '.join(findings) or 'none'} "
        f"(log: {work / 'last.log'})"
    )
    if findings:
        tail = [line for line in logs[-1].splitlines() if "Error" in line or "Traceback" in line or "==" in line]
        print("\n".join(tail[-12:]))
    return 1 if findings else 0


def _libfuzzer(target: str, found: Path, work: Path, seconds: int, runs: int | None = None) -> str:
    """One atheris run in a subprocess (of at most `runs` executions); its output."""
    import fuzz_targets

    command = [
        sys.executable,
        __file__,
        "--worker",
        target,
        str(found),
        str(fuzz_targets.CORPUS / target),
        f"-max_total_time={seconds}",
        f"-timeout={int(fuzz_targets.LIMIT_S)}",
        f"-rss_limit_mb={fuzz_targets.MEMORY_MB}",
        f"-max_len={fuzz_targets.MAX_LEN}",
        f"-artifact_prefix={work}/",
        "-print_final_stats=1",
        *([f"-runs={runs}"] if runs else []),
    ]
    proc = subprocess.run(command, capture_output=True, text=True, errors="replace", check=False)
    return proc.stdout + proc.stderr


def _replay(target: str, path: Path) -> tuple[float, float]:
    """(seconds, peak resident MB) of the input alone, in a fresh process, once the target is
    warm (the best of 3 times)."""
    code = (
        "import resource, sys, time; sys.path.insert(0, sys.argv[1]); import fuzz_targets as f; f.warm(sys.argv[2]); "
        "d = open(sys.argv[3], 'rb').read(); t = []\n"
        "for _ in range(3):\n s = time.perf_counter(); f.run_one(sys.argv[2], d); t.append(time.perf_counter() - s)\n"
        "print(min(t), resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)"
    )
    try:
        proc = subprocess.run(
            [sys.executable, "-c", code, str(TESTS), target, str(path)], capture_output=True, text=True, timeout=120
        )
        took, mb = proc.stdout.strip().splitlines()[-1].split()
        return float(took), float(mb)
    except (ValueError, IndexError, subprocess.TimeoutExpired):
        return float("inf"), float("inf")  # it failed or hung alone: a finding


def _worker(target: str, libfuzzer_args: list[str]) -> int:
    import atheris

    with atheris.instrument_imports(include=["rtta"]):
        import fuzz_targets

        import rtta.renderer.options  # noqa: F401  (instrumented here, before a target imports it lazily)
        import rtta.renderer.snapshot  # noqa: F401
        import rtta.scene

        for module in pkgutil.walk_packages(rtta.scene.__path__, "rtta.scene."):
            if module.name.rpartition(".")[2] not in ("usd", "collada", "threedxml", "draco"):  # not fuzzed here
                importlib.import_module(module.name)

    def one(data: bytes) -> None:
        fuzz_targets.run_one(target, data)

    atheris.Setup([sys.argv[0], *libfuzzer_args], one)
    atheris.Fuzz()
    return 0


if __name__ == "__main__":
    sys.exit(main())
