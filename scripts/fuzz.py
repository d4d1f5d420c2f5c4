"""Coverage-guided fuzzing of rtta's own parsers with atheris (libFuzzer), one target at a
time, in a subprocess (issue 42; the targets are in tests/fuzz_targets.py).

    python scripts/fuzz.py TARGET [--seconds N] [--work DIR]    run TARGET for N seconds (60)
    python scripts/fuzz.py --corpus                             (re)write tests/fuzz_corpus/
    python scripts/fuzz.py --list                               the targets

The contract: an input gives a result or an RttaError; any other exception, more than 2 s
(libFuzzer's -timeout) or more than 2048 MB resident (-rss_limit_mb) is a finding, saved as
DIR/crash-*, timeout-* or oom-* (DIR: /tmp/rtta-fuzz/TARGET, whose corpus/ keeps what the run
found, beside the seeds of tests/fuzz_corpus/TARGET). Prints the executions, coverage and
findings; exits 1 when there are findings. Run one at a time, niced, on a shared machine.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1] / "tests"
sys.path.insert(0, str(TESTS))


def main() -> int:
    if len(sys.argv) > 2 and sys.argv[1] == "--worker":
        return _worker(sys.argv[2], sys.argv[3:])
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("target", nargs="?")
    parser.add_argument("--seconds", type=int, default=60)
    parser.add_argument("--work", type=Path, default=None)
    parser.add_argument("--corpus", action="store_true", help="(re)write the seed corpora")
    parser.add_argument("--list", action="store_true")
    args = parser.parse_args()
    import fuzz_targets

    if args.list:
        print("\n".join(fuzz_targets.TARGETS))
        return 0
    if args.corpus:
        from fuzz_corpus_make import write_corpus

        for target, count in write_corpus(fuzz_targets.CORPUS).items():
            print(f"{target}: {count} seeds")
        return 0
    if args.target not in fuzz_targets.TARGETS:
        parser.error(f"TARGET must be one of {', '.join(fuzz_targets.TARGETS)}")
    return _run(args.target, args.seconds, args.work or Path("/tmp/rtta-fuzz") / args.target)


def _run(target: str, seconds: int, work: Path) -> int:
    import fuzz_targets

    found = work / "corpus"
    found.mkdir(parents=True, exist_ok=True)
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
    ]
    before = {p.name for p in work.iterdir()}
    proc = subprocess.run(command, capture_output=True, text=True, errors="replace", check=False)
    log = proc.stdout + proc.stderr
    (work / "last.log").write_text(log)
    findings = sorted(
        p.name for p in work.iterdir() if p.name not in before and re.match(r"(crash|timeout|oom|slow)", p.name)
    )
    cov = re.findall(r"cov: (\d+) ft: (\d+)", log)
    runs = re.findall(r"stat::number_of_executed_units:\s*(\d+)", log)
    print(
        f"{target}: {runs[-1] if runs else '?'} executions in {seconds} s, "
        f"coverage {cov[-1][0] if cov else '?'} edges / {cov[-1][1] if cov else '?'} features, "
        f"corpus {len(list(found.iterdir()))} found + {len(list((fuzz_targets.CORPUS / target).iterdir()))} seeds, "
        f"findings: {', '.join(findings) or 'none'} (log: {work / 'last.log'})"
    )
    if findings:
        tail = [line for line in log.splitlines() if "Error" in line or "Traceback" in line or "==" in line]
        print("\n".join(tail[-12:]))
    return 1 if findings or proc.returncode not in (0,) else 0


def _worker(target: str, libfuzzer_args: list[str]) -> int:
    import atheris

    with atheris.instrument_imports(include=["rtta"]):
        import fuzz_targets

        import rtta.renderer.options  # noqa: F401  (instrumented before a target imports it)
        import rtta.renderer.snapshot  # noqa: F401
        import rtta.scene.loader  # noqa: F401
        import rtta.scene.readers.ifc  # noqa: F401
        import rtta.scene.readers.step  # noqa: F401

    def one(data: bytes) -> None:
        fuzz_targets.run_one(target, data)

    atheris.Setup([sys.argv[0], *libfuzzer_args], one)
    atheris.Fuzz()
    return 0


if __name__ == "__main__":
    sys.exit(main())
