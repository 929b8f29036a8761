#!/usr/bin/env python3
"""Run a faceanim batch manifest on a Ray cluster: one Ray task per row.

Each task runs the worker contract of `faceanim batch` on the node it lands on:

    faceanim batch MANIFEST --index N --progress json

and reads its exit status: 0 the row is done or skipped, 42 its input is bad (reported, never
retried), anything else a failure of the machine (raised, so Ray retries the task). A node or
worker that dies mid-row is a system failure that Ray retries too; the row's own lock and its
atomic outputs make the retry safe, and the worker's faceanim process dies with the worker.

Before any task, `faceanim batch MANIFEST --plan --all` says where every row stands: rows whose
record matches are skipped without a task, bad rows are reported without one.

Every node needs the faceanim binary (--faceanim, or `faceanim` on its PATH) and the
manifest's folder at the same path (a shared file system). Usage:

    ray start --head                      # or an existing cluster
    python3 faceanim_ray.py lines.jsonl --faceanim /opt/faceanim/bin/faceanim

The report (JSON, every row's result) goes to --report (default MANIFEST.ray-report.json), a
summary to standard output. Exit status: 0 when every row is done, skipped or kept; 42 when
some rows' input is bad; 1 when some failed even after their retries.
"""

import argparse
import ctypes
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

import ray

EXIT_BAD_INPUT = 42


class TransientFailure(Exception):
    """A row that failed for the machine's reasons: worth running again."""


PR_SET_PDEATHSIG = 1


def _prctl():
    """libc's prctl, loaded in the calling process (the Ray worker): a child forked from a
    threaded process may only do what takes no lock, and loading a library takes the loader's."""
    try:
        return ctypes.CDLL("libc.so.6", use_errno=True).prctl
    except (OSError, AttributeError):
        return None


def _events(stderr):
    """The JSON events of a worker's standard error, and its other lines."""
    events, other = [], []
    for line in stderr.splitlines():
        try:
            event = json.loads(line)
        except ValueError:
            other.append(line)
            continue
        if isinstance(event, dict) and "event" in event:
            events.append(event)
        else:
            other.append(line)
    return events, other


@ray.remote
def run_row(faceanim, manifest, index, flags):
    """Runs row `index` with the worker contract; returns its result, raises on a transient
    failure."""
    started = time.monotonic()
    prctl = _prctl()

    def die_with_parent():
        # In the child, before faceanim starts: it dies when this Ray worker dies (Linux), so a
        # killed worker leaves no faceanim running its row beside the retry.
        if prctl is not None:
            prctl(PR_SET_PDEATHSIG, signal.SIGKILL)

    process = subprocess.run(
        [faceanim, "batch", manifest, "--index", str(index), "--progress", "json", *flags],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=die_with_parent,
    )
    events, other = _events(process.stderr)
    rows = [e for e in events if e.get("event") == "row"]
    if process.returncode in (0, EXIT_BAD_INPUT) and rows:
        result = rows[-1]
        result.pop("event", None)
        result["exit"] = process.returncode
        result["node"] = ray.get_runtime_context().get_node_id()
        result["task_seconds"] = time.monotonic() - started
        return result
    tail = "\n".join(other[-10:])
    raise TransientFailure(f"row {index}: faceanim exited {process.returncode}: {tail}")


def plan(faceanim, manifest, flags):
    """Where every row stands, as `faceanim batch --plan` says."""
    process = subprocess.run(
        [faceanim, "batch", manifest, "--plan", "--all", *flags],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    if process.returncode != 0:
        sys.stderr.write(process.stderr)
        sys.exit(process.returncode)
    return [json.loads(line) for line in process.stdout.splitlines() if line.strip()]


def settled(row, status, exit_code):
    """A row's result decided by the plan, without a task."""
    result = {
        "index": row["index"],
        "line": row["line"],
        "id": row["id"],
        "status": status,
        "seconds": 0.0,
        "attempts": 0,
        "exit": exit_code,
    }
    if status == "bad_input":
        result["error"] = row.get("detail")
    elif row.get("detail"):
        result["reason"] = row["detail"]
    return result


def summary(report):
    counts = ", ".join(f"{n} {status}" for status, n in sorted(report["counts"].items()))
    text = f"{report['manifest']}: {len(report['rows'])} rows in {report['seconds']:.1f} s: {counts}"
    done = report["counts"].get("done", 0)
    if done and report["seconds"] > 0:
        text += f" ({done * 60 / report['seconds']:.0f} rows a minute)"
    lines = [text]
    for row in report["rows"]:
        if row["status"] in ("bad_input", "failed", "edited"):
            note = row.get("error") or row.get("reason") or ""
            lines.append(f"  line {row['line']} ({row['id']}): {row['status']}: {note}")
    return "\n".join(lines)


def write_atomic(path, text):
    folder = os.path.dirname(os.path.abspath(path))
    with tempfile.NamedTemporaryFile("w", dir=folder, delete=False, suffix=".tmp") as file:
        file.write(text)
        file.flush()
        os.fsync(file.fileno())
    os.replace(file.name, path)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("manifest", help="the manifest (JSON Lines or CSV)")
    parser.add_argument("--faceanim", default="faceanim", help="the faceanim binary on every node")
    parser.add_argument("--address", default="auto", help="the Ray cluster (default: auto)")
    parser.add_argument("--retries", type=int, default=3, help="retries of a row that failed for the machine's reasons")
    parser.add_argument("--cpus-per-row", type=float, default=1.0, help="CPUs a row takes on its node")
    parser.add_argument("--force", action="store_true", help="redo rows whose record matches")
    parser.add_argument("--overwrite-edits", action="store_true", help="overwrite outputs edited since")
    parser.add_argument("--report", help="the report (default: MANIFEST.ray-report.json)")
    args = parser.parse_args(argv)

    started = time.monotonic()
    manifest = os.path.abspath(args.manifest)
    faceanim = args.faceanim
    flags = (["--force"] if args.force else []) + (["--overwrite-edits"] if args.overwrite_edits else [])
    rows = plan(faceanim, manifest, flags)

    results = []
    to_run = []
    for row in rows:
        if row["state"] == "to_run":
            to_run.append(row)
        elif row["state"] == "bad_input":
            results.append(settled(row, "bad_input", EXIT_BAD_INPUT))
        else:
            results.append(settled(row, row["state"], 0))

    pending = {}
    if to_run:
        # Nothing to run (a second run): no cluster needed.
        ray.init(address=args.address, log_to_driver=False)
        task = run_row.options(
            num_cpus=args.cpus_per_row,
            max_retries=args.retries,
            retry_exceptions=[TransientFailure],
        )
        pending = {task.remote(faceanim, manifest, row["index"], flags): row for row in to_run}
    while pending:
        # Whatever has finished (up to 64 at a time), without a busy loop.
        ready, _ = ray.wait(list(pending), num_returns=min(64, len(pending)), timeout=1.0)
        for ref in ready:
            row = pending.pop(ref)
            try:
                result = ray.get(ref)
            except Exception as error:  # retries spent: a task error or a worker that kept dying
                result = settled(row, "failed", 1)
                result["error"] = str(error).strip().splitlines()[-1] if str(error).strip() else repr(error)
            results.append(result)
            print(json.dumps({"event": "row", **result}), file=sys.stderr, flush=True)

    results.sort(key=lambda r: r["index"])
    counts = {}
    for result in results:
        counts[result["status"]] = counts.get(result["status"], 0) + 1
    report = {
        "manifest": manifest,
        "seconds": time.monotonic() - started,
        "counts": counts,
        "rows": results,
    }
    report_path = args.report or manifest + ".ray-report.json"
    write_atomic(report_path, json.dumps(report, indent=2) + "\n")
    print(summary(report))
    print(f"report: {report_path}")
    if counts.get("failed"):
        return 1
    if counts.get("bad_input"):
        return EXIT_BAD_INPUT
    return 0


if __name__ == "__main__":
    sys.exit(main())
