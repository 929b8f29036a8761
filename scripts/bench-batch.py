#!/usr/bin/env python3
"""`faceanim batch` as a studio runs it, timed as a whole command: a manifest of speech lines
(flite's voices saying made-up dialogue, tools/batch_lines.py, one row in fifty broken on
purpose) run with `--jobs N` on this machine, then on a local two-node Ray cluster (one CPU
each) through deploy/ray/faceanim_ray.py.

Measures: lines a minute; the second run (nothing to do); a changed transcript; an edited take;
the worker's own cost per row (a worker started for a row that is already done: process start,
manifest, hashing); Ray's cost per task (no-op tasks, and the run's wall time against the rows'
own time). Prints one JSON object (and writes it to target/bench-batch/result.json).

Usage: scripts/bench-batch.py [--lines 1000] [--jobs 2] [--no-build] [--no-ray]
"""

import argparse
import json
import os
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import wave

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FACEANIM = os.path.join(REPO, "target", "release", "faceanim")
OUT = os.path.join(REPO, "target", "bench-batch")


def timed(command, **kwargs):
    started = time.monotonic()
    process = subprocess.run(command, capture_output=True, text=True, **kwargs)
    return time.monotonic() - started, process


def events(stderr):
    rows = []
    for line in stderr.splitlines():
        try:
            event = json.loads(line)
        except ValueError:
            continue
        if isinstance(event, dict) and event.get("event") == "row":
            rows.append(event)
    return rows


def counts(rows):
    result = {}
    for row in rows:
        result[row["status"]] = result.get(row["status"], 0) + 1
    return result


def batch(dir, *args):
    seconds, process = timed([FACEANIM, "batch", "lines.jsonl", "--progress", "json", *args], cwd=dir)
    return seconds, process.returncode, events(process.stderr)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def ray_noop_overhead(address, tasks=400):
    """Seconds per task of Ray alone: no-op tasks that start a process each, as a row does."""
    script = f"""
import ray, subprocess, time
ray.init(address="{address}", log_to_driver=False)
@ray.remote(num_cpus=1)
def row():
    subprocess.run(["true"])
ray.get([row.remote() for _ in range(20)])
started = time.monotonic()
ray.get([row.remote() for _ in range({tasks})])
print((time.monotonic() - started) / {tasks})
"""
    process = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    return float(process.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--lines", type=int, default=1000)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--no-build", action="store_true")
    parser.add_argument("--no-ray", action="store_true")
    args = parser.parse_args()
    if not args.no_build:
        subprocess.run(["cargo", "build", "--release", "--locked", "-p", "faceanim"], cwd=REPO, check=True,
                       stdout=sys.stderr)
    dir = os.path.join(OUT, "lines")
    shutil.rmtree(dir, ignore_errors=True)
    os.makedirs(dir)
    started = time.monotonic()
    made = json.loads(subprocess.run(
        [sys.executable, os.path.join(REPO, "tools", "batch_lines.py"), dir, "--lines", str(args.lines),
         "--broken", str(max(1, args.lines // 50))], capture_output=True, text=True, check=True).stdout)
    making = time.monotonic() - started
    broken = sum(1 for r in made["rows"] if r["broken"])
    good = args.lines - broken
    result = {"lines": args.lines, "broken": broken, "jobs": args.jobs, "cpus": os.cpu_count(),
              "making_lines_seconds": making}

    # The whole batch with --jobs.
    seconds, code, rows = batch(dir, "--jobs", str(args.jobs))
    by_status = counts(rows)
    assert by_status.get("done") == good, by_status
    assert by_status.get("bad_input") == broken, by_status
    assert code == 42, code
    speech = 0.0
    for row in made["rows"]:
        if not row["broken"]:
            with wave.open(os.path.join(dir, "audio", f"{row['id']}.wav")) as audio:
                speech += audio.getnframes() / audio.getframerate()
    result["speech_seconds"] = speech
    worker_seconds = [r["seconds"] for r in rows if r["status"] == "done"]
    result["jobs_run"] = {
        "seconds": seconds,
        "lines_per_minute": good * 60 / seconds,
        "speech_seconds_per_second": speech / seconds,
        "exit": code,
        "counts": by_status,
        "row_seconds_median": statistics.median(worker_seconds),
        "retried": sum(1 for r in rows if r.get("attempts", 1) > 1),
    }

    # Again: nothing to do.
    seconds, code, rows = batch(dir, "--jobs", str(args.jobs))
    result["second_run"] = {"seconds": seconds, "counts": counts(rows)}
    assert counts(rows).get("skipped") == good

    # A changed transcript.
    changed = next(r for r in made["rows"] if not r["broken"] and r["index"] % 10 == 3)
    with open(os.path.join(dir, "text", f"{changed['id']}.txt"), "w") as file:
        file.write("Bob bought a map of the bay.\n")
    seconds, code, rows = batch(dir, "--jobs", str(args.jobs))
    done = [r["id"] for r in rows if r["status"] == "done"]
    result["changed_transcript"] = {"seconds": seconds, "done": done}
    assert done == [changed["id"]], done

    # An edited take, its line delivered again: kept.
    edited = next(r for r in made["rows"] if not r["broken"] and r["index"] % 10 != 3)
    take = os.path.join(dir, "out", f"{edited['id']}.json")
    with open(take) as file:
        clip = json.load(file)
    clip["name"] = "polished in the studio"
    with open(take, "w") as file:
        json.dump(clip, file)
    subprocess.run(["flite", "-voice", "kal16", "-t", edited["words"], "-o",
                    os.path.join(dir, "audio", f"{edited['id']}.wav")], check=True)
    seconds, code, rows = batch(dir, "--jobs", str(args.jobs))
    status = {r["id"]: r["status"] for r in rows}
    result["edited_take"] = {"seconds": seconds, "status": status[edited["id"]]}
    assert status[edited["id"]] == "edited"

    # The worker's own cost: a worker started for a row already done.
    index = next(r["index"] for r in made["rows"] if not r["broken"] and r["id"] != edited["id"])
    costs = []
    for _ in range(20):
        seconds, process = timed([FACEANIM, "batch", "lines.jsonl", "--index", str(index), "--progress", "none"],
                                 cwd=dir)
        costs.append(seconds)
    result["worker_overhead_seconds_median"] = statistics.median(costs)

    if not args.no_ray:
        shutil.rmtree(os.path.join(dir, "out"))
        os.remove(os.path.join(dir, "lines.jsonl.report.json"))
        port = free_port()
        temp = tempfile.mkdtemp(prefix="faceanim-ray-")
        env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0")
        address = f"127.0.0.1:{port}"
        try:
            subprocess.run(["ray", "start", "--head", "--node-ip-address", "127.0.0.1", "--port", str(port),
                            "--num-cpus", "1", "--include-dashboard", "false", "--disable-usage-stats",
                            "--temp-dir", temp], check=True, capture_output=True, env=env)
            subprocess.run(["ray", "start", "--address", address, "--node-ip-address", "127.0.0.1",
                            "--num-cpus", "1"], check=True, capture_output=True, env=env)
            seconds, process = timed([sys.executable, os.path.join(REPO, "deploy", "ray", "faceanim_ray.py"),
                                      os.path.join(dir, "lines.jsonl"), "--faceanim", FACEANIM,
                                      "--address", address], env=env)
            with open(os.path.join(dir, "lines.jsonl.ray-report.json")) as file:
                report = json.load(file)
            assert report["counts"].get("done") == good, report["counts"]
            assert report["counts"].get("bad_input") == broken, report["counts"]
            tasks = [r for r in report["rows"] if "task_seconds" in r]
            task_seconds = sum(r["task_seconds"] for r in tasks)
            own_seconds = sum(r["seconds"] for r in tasks)
            result["ray_run"] = {
                "nodes": 2,
                "seconds": seconds,
                "lines_per_minute": good * 60 / seconds,
                "exit": process.returncode,
                "counts": report["counts"],
                # Per task: what the two CPUs spent beyond the tasks' own time (scheduling,
                # Python, plan), and beyond the rows' own time inside faceanim (process start too).
                "per_task_scheduling_seconds": (2 * seconds - task_seconds) / len(tasks),
                "per_task_outside_row_seconds": (task_seconds - own_seconds) / len(tasks),
            }
            seconds, process = timed([sys.executable, os.path.join(REPO, "deploy", "ray", "faceanim_ray.py"),
                                      os.path.join(dir, "lines.jsonl"), "--faceanim", FACEANIM,
                                      "--address", address], env=env)
            result["ray_second_run_seconds"] = seconds
            result["ray_noop_task_seconds"] = ray_noop_overhead(address)
        finally:
            subprocess.run(["ray", "stop", "--force"], capture_output=True)
            shutil.rmtree(temp, ignore_errors=True)

    text = json.dumps(result, indent=2)
    with open(os.path.join(OUT, "result.json"), "w") as file:
        file.write(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
