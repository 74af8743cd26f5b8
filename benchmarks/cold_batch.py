"""The first ``batch`` on an empty kernel cache (issue 30, item 3): how soon the compile
notice appears, and whether the batch costs one compile plus the jobs (the kernels are
compiled once, in the parent, before the workers start; the workers load them).

    python benchmarks/cold_batch.py [--jobs 4] [--workers 2] [--json out/bench/cold_batch.json]

Three runs, each in a fresh interpreter:
1. ``batch`` with an empty cache: the seconds until the notice line, and the wall time W1;
2. the same ``batch`` again, the cache now warm: W2 (starting the workers and the jobs);
3. the compile alone with another empty cache (the batch's warm-up in one process): C.
The batch is within its budget when W1 <= C + W2 (plus a few per cent of noise).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _timed(argv: list[str], cache: Path) -> tuple[float, float | None, str]:
    """Wall seconds, seconds to the compile notice (None: none), and stderr."""
    env = dict(os.environ, SUBTASK_OPT_CACHE_DIR=str(cache), PYTHONPATH=str(ROOT),
               MPLBACKEND="Agg")
    start = time.monotonic()
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True)
    notice: list[float] = []
    lines: list[str] = []

    def read() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            if "compiling" in line and not notice:
                notice.append(time.monotonic() - start)
            lines.append(line)

    reader = threading.Thread(target=read)
    reader.start()
    proc.wait()
    reader.join()
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} exited {proc.returncode}:\n{''.join(lines)}")
    return time.monotonic() - start, notice[0] if notice else None, "".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--jobs", type=int, default=4)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--subtasks", type=int, default=20)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    from subtask_opt.arm.tasks import random_subtasks, save_subtasks
    from subtask_opt.kinematics.planar import load_planar_arm

    arm = load_planar_arm("planar_2r")
    with tempfile.TemporaryDirectory(prefix="cold-batch-") as tmp:
        folder = Path(tmp)
        files = []
        for i in range(args.jobs):
            path = folder / f"part{i}.csv"
            save_subtasks(random_subtasks(arm, args.subtasks, seed=i), path)
            files.append(str(path))
        batch = [sys.executable, "-m", "subtask_opt.cli", "batch", *files, "--workers",
                 str(args.workers), "--no-progress", "--json", str(folder / "out.json")]
        cold, latency, err = _timed(batch, folder / "cache-a")
        warm, _, _ = _timed(batch, folder / "cache-a")
        compile_only, _, _ = _timed([sys.executable, "-c", "from subtask_opt.batch.jobs import "
                                     "warm_up; warm_up((('joint', 'optimize'),))"],
                                    folder / "cache-b")
        jobs = json.loads((folder / "out.json").read_text())["summary"]["jobs_time_s"]
    notice = next((ln for ln in err.splitlines() if "compiling" in ln), "")
    rows = {"jobs": args.jobs, "workers": args.workers, "notice_after_s": latency,
            "cold_batch_s": cold, "warm_batch_s": warm, "compile_alone_s": compile_only,
            "budget_s": compile_only + warm, "jobs_time_s": jobs,
            "within_budget": cold <= 1.05 * (compile_only + warm), "notice": notice,
            "cpus": os.cpu_count(), "load_average": os.getloadavg()}
    print(f"notice after {latency:.2f} s: {notice}")
    print(f"cold batch {cold:.1f} s; compile alone {compile_only:.1f} s + warm batch "
          f"{warm:.1f} s = {compile_only + warm:.1f} s "
          f"({'within' if rows['within_budget'] else 'OVER'} one compile plus the jobs); "
          f"the jobs themselves {jobs:.1f} s; load average {os.getloadavg()[0]:.1f} on "
          f"{os.cpu_count()} cores")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")
    return 0 if rows["within_budget"] and latency is not None and latency <= 2.0 else 1


if __name__ == "__main__":
    sys.exit(main())
