"""`repose batch MANIFEST --out DIR`: prepares every subject once, then fans its poses and clip frames
out over a Dask cluster (a local one by default), skipping what is complete, and keeps the record."""
import argparse
import asyncio
import importlib.util
import logging
import os
import shutil
import sys
import threading
import time
import uuid
from datetime import datetime, timezone

from . import records, store
from .manifest import ManifestError, load_manifest
from .plan import file_hash, plan_batch
from .progress import Progress, duration

USAGE = """repose batch MANIFEST --out DIR [--workers N | --scheduler ADDRESS] [--task-timeout SECONDS] [--retry-failed]
       [--dry-run]"""
DESCRIPTION = """Many subjects x many poses and BVH frames, on Dask. MANIFEST (YAML or JSON, see docs/batch.md)
names the subjects (labels, optional CT, skeleton or auto, label table) and what to make of each (poses,
clips with frame ranges, skinning, relaxation, outputs, format). Each subject is prepared once
(DIR/SUBJECT/case, as `repose prepare`), then every pose (DIR/SUBJECT/poses/POSE) and frame
(DIR/SUBJECT/clips/CLIP/frame_NNNNN) is posed as `repose pose` poses it, on the cluster's workers.
Results are written atomically; a rerun skips every result already complete for the same inputs and
settings (and tasks that failed before, unless --retry-failed). DIR/batch.csv has one row per task
(status, times, body volume ratio, worst bone Dice against its rigid motion, inverted tets);
DIR/batch.json the exact inputs with their sha256, the settings and the versions. Exit status 1 when a
task failed (its message is in both records)."""


WORKER_WAIT_SECONDS = 60  # the workers of a cluster just started (Slurm, Kubernetes) come in after its scheduler
CLUSTER_START_SECONDS = 120  # a local cluster whose worker died while starting never finishes starting (Dask)
STALL_SECONDS = 120  # tasks pending while every worker is idle this long were lost by the cluster
LOST_TRIES = 3  # submissions of a task the cluster keeps losing before it is reported failed
TASK_TIMEOUT_SECONDS = 4 * 3600  # a task running longer hangs (the largest FEM poses take minutes)


class UsageError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(message)


def parse_args(argv):
    p = _Parser(prog="repose batch", usage=USAGE, description=DESCRIPTION,
                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("manifest", metavar="MANIFEST", help="the batch manifest (.yaml, .yml or .json)")
    p.add_argument("--out", required=True, metavar="DIR", help="results and records (created if missing)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="workers of the local cluster (default: one per core; each runs one task at a time)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="an existing Dask scheduler (tcp://host:8786) instead of a local cluster; its workers need "
                        "this build at the same path, this package on PYTHONPATH and DIR on a shared file system")
    p.add_argument("--task-timeout", type=float, default=TASK_TIMEOUT_SECONDS, metavar="SECONDS",
                   help="a task running longer than this on a worker is stopped, its worker restarted and the task "
                        f"recorded as failed (default {TASK_TIMEOUT_SECONDS} s; 0: no limit)")
    p.add_argument("--retry-failed", action="store_true", help="run again the tasks that failed before")
    p.add_argument("--dry-run", action="store_true", help="list what would run and what is complete, run nothing")
    args = p.parse_args(argv)
    if args.workers is not None and args.workers < 1:
        raise UsageError("--workers must be at least 1")
    if not args.task_timeout >= 0:
        raise UsageError("--task-timeout must be a number of seconds >= 0")
    if args.workers is not None and args.scheduler:
        raise UsageError("--workers is for the local cluster; a --scheduler has its own workers")
    return args


def _now():
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds")


def _describe(task):
    """The client's part of a task's record: what it is and its exact inputs."""
    inputs = {"pose": task.get("pose"), "clip": task.get("clip"), "frame": task.get("frame"),
              "retarget": task.get("retarget")}
    return {"kind": task["kind"], "subject": task["subject"], "task": task["task"], "key": task["key"],
            "out": task["out"], "inputs": {k: v for k, v in inputs.items() if v is not None}}


def _triage(tasks, retry_failed, out_dir):
    """Each task's starting record: complete results are skipped, earlier failures kept unless retried."""
    failed_before = records.previous_failures(out_dir)
    start, to_run = [], []
    for t in tasks:
        done = store.completed(t["out"], t["key"])
        if done:
            start.append({**done, **_describe(t), "status": "skipped", "ran": "earlier"})
        elif t["key"] in failed_before and not retry_failed:
            start.append({**failed_before[t["key"]], **_describe(t), "status": "failed", "ran": "earlier"})
        else:
            start.append({**_describe(t), "status": "not run", "ran": ""})
            to_run.append(t)
    return start, to_run


def _connect(args):
    """(client, cluster or None, threads per worker for the filters, dashboard link or "")."""
    from distributed import Client, LocalCluster
    if args.scheduler:
        client = Client(args.scheduler, timeout="30s")
        link = client.dashboard_link if "dashboard" in client.scheduler_info().get("services", {}) else ""
        return client, None, 0, link
    cores = os.cpu_count() or 1
    workers = args.workers or cores
    bokeh = importlib.util.find_spec("bokeh") is not None  # Dask's dashboard needs it (not in Debian 12)
    cluster = _bounded(lambda: LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                            dashboard_address=":0" if bokeh else None, silence_logs=logging.CRITICAL),
                       CLUSTER_START_SECONDS, "the local cluster did not start (a worker died while starting); run again")
    client = Client(cluster)
    return client, cluster, max(1, cores // workers), client.dashboard_link if bokeh else ""


def _bounded(start, seconds, problem):
    """start() in a thread, waited for at most `seconds`: Dask's start hangs for good when a worker dies during it."""
    box = {}

    def call():
        try:
            box["value"] = start()
        except BaseException as e:  # noqa: BLE001 - raised again in the caller's thread
            box["error"] = e

    thread = threading.Thread(target=call, daemon=True)
    thread.start()
    thread.join(seconds)
    if thread.is_alive():
        raise RuntimeError(f"{problem} (nothing after {seconds} s)")
    if "error" in box:
        raise box["error"]
    return box["value"]


def _check_workers(client, executable):
    """Every worker of an existing cluster must import this package and see this build."""
    def probe(path=executable):
        try:
            import repose  # noqa: F401
            from repose import vtkReposeSkeletonPoses  # noqa: F401
        except ImportError as e:
            return f"cannot import the repose package ({e}); start the worker with PYTHONPATH set to it"
        return "" if os.access(path, os.X_OK) else f"{path}: not found on the worker (the same build is needed there)"

    if not client.scheduler_info()["workers"]:
        print(f"batch: waiting up to {WORKER_WAIT_SECONDS} s for a worker of {client.scheduler.address}", flush=True)
        try:
            client.wait_for_workers(1, timeout=WORKER_WAIT_SECONDS)
        except Exception:  # noqa: BLE001 - Dask's TimeoutError (asyncio's or its own, by version)
            raise RuntimeError(f"the scheduler {client.scheduler.address} has no workers "
                               f"(none came in {WORKER_WAIT_SECONDS} s)") from None
    answers = client.run(probe)
    for worker, problem in sorted(answers.items()):
        if problem:
            raise RuntimeError(f"worker {worker}: {problem}")
    return len(answers)


class _Submitter:
    """Submits the tasks to run: prepares first, then each subject's poses once its prepare has ended.
    A pose gets its prepare's record (a small dict), not its future: no result travels between workers,
    where Dask 2022.12 can leave a task fetching from a lost worker for good."""

    def __init__(self, client, to_run, start, threads):
        self.client, self.threads = client, threads
        self.run_id = uuid.uuid4().hex[:8]
        self.futures = {}  # future -> task
        self.tries = {}  # task key -> submissions
        # One subject's poses before the next's: a worker then loads each case once, not at every switch.
        self.order = {name: i for i, name in enumerate(dict.fromkeys(r["subject"] for r in start))}
        self.waiting = {}  # subject -> its poses, until its prepare ends
        for t in to_run:
            if t["kind"] != "prepare":
                self.waiting.setdefault(t["subject"], []).append(t)
        for t in to_run:
            if t["kind"] == "prepare":
                self.submit(t)
        # Subjects prepared before (complete, or failed and not retried): their poses go now.
        for r in start:
            if r["kind"] == "prepare" and r["subject"] in self.waiting and r["status"] != "not run":
                self.prepared(r["subject"], {"status": "done" if r["status"] == "skipped" else r["status"],
                                             "message": r.get("message", "")})

    def submit(self, t, prepared=None):
        from .tasks import pose_task, prepare_subject
        n = self.tries[t["out"]] = self.tries.get(t["out"], 0) + 1
        if t["kind"] == "prepare":
            f = self.client.submit(prepare_subject, t, key=f"prepare-{self.run_id}-{t['subject']}-{n}",
                                   priority=10, pure=False)
        else:
            # Dask groups tasks by their keys' words before the run id, so all poses are one group, ordered as one.
            f = self.client.submit(pose_task, prepared, {**t, "threads": self.threads},
                                   key=f"{t['kind']}-{self.run_id}-{t['subject']}-{t['task']}-{n}",
                                   priority=-self.order[t["subject"]], pure=False)
            f.prepared = prepared
        self.futures[f] = t
        return f

    def prepared(self, subject, record):
        """The subject's prepare has ended (done or failed): its poses are submitted with its record."""
        for t in self.waiting.pop(subject, []):
            self.submit(t, {"status": record["status"], "message": record.get("message", "")})

    def resubmit(self, future):
        """The same task under a new key, for a future the cluster lost."""
        t = self.futures.pop(future)
        self.client.cancel([future])
        return self.submit(t, getattr(future, "prepared", None))


def _header(args, manifest, subjects, run):
    return {"format": "repose-batch", "versions": records.versions(),
            "manifest": {"path": manifest["path"], "sha256": file_hash(manifest["path"]), "content": manifest["data"]},
            "command": ["repose", "batch", *sys.argv[1:]],
            "settings": {"scheduler": args.scheduler or "local", "workers": run.get("workers"),
                         "task_timeout_s": args.task_timeout,
                         "retry_failed": args.retry_failed},
            "subjects": subjects, "run": run}


def _run(args, manifest, subjects, tasks, out_dir, executable):
    start, to_run = _triage(tasks, args.retry_failed, out_dir)
    run = {"started": _now(), "tasks": len(tasks), "to_run": len(to_run)}
    by_out = {r["out"]: i for i, r in enumerate(start)}  # a key repeats when a result is asked twice
    print(f"batch: {len(subjects)} subjects, {len(tasks)} tasks: {len(to_run)} to run, "
          f"{sum(r['status'] == 'skipped' for r in start)} complete before, "
          f"{sum(r['status'] == 'failed' for r in start)} failed before"
          f"{' (not retried: --retry-failed)' if any(r['status'] == 'failed' for r in start) else ''}", flush=True)
    if args.dry_run:
        for r in start:
            print(f"  {r['subject']:<20} {r['task']:<28} {'would run' if r['status'] == 'not run' else r['status']}")
        return start, run
    t0 = time.monotonic()
    if to_run:
        client, cluster, threads, link = _connect(args)
        try:
            run["workers"] = _check_workers(client, executable) if args.scheduler else len(client.nthreads())
            print(f"batch: {run['workers']} worker{'s' if run['workers'] != 1 else ''} on "
                  f"{args.scheduler or 'a local cluster'}" + (f", dashboard {link}" if link else ""), flush=True)
            run["dashboard"] = link
            submitter = _Submitter(client, to_run, start, threads)
            _collect(client, submitter, start, by_out, args, manifest, subjects, run, out_dir)
        finally:
            client.close()
            if cluster:
                cluster.close()
        store.sweep(out_dir)  # every task has ended: what is left half-written belonged to lost workers
    run["finished"], run["seconds"] = _now(), round(time.monotonic() - t0, 3)
    posed = sum(r["ran"] == "this" and r["status"] == "done" and r["kind"] != "prepare" for r in start)
    run["poses_done"] = posed
    run["poses_per_minute"] = round(60.0 * posed / run["seconds"], 3) if posed and run["seconds"] > 0 else None
    return start, run


def _collect(client, submitter, start, by_out, args, manifest, subjects, run, out_dir):
    from distributed import wait
    progress = Progress(len(submitter.futures) + sum(len(v) for v in submitter.waiting.values()))
    last_write = 0.0
    workers = set(client.scheduler_info()["workers"])
    pending = set(submitter.futures)
    watch = _StallWatch(client, submitter, progress)
    timeout = _TaskTimeout(client, submitter, progress, args.task_timeout)

    def record(t, result):
        r = start[by_out[t["out"]]] = {**_describe(t), **result, "ran": "this"}
        if t["kind"] == "prepare":
            before = set(submitter.futures)
            submitter.prepared(t["subject"], r)
            pending.update(set(submitter.futures) - before)
        if r["status"] != "done":
            progress.note(f"batch: failed: {t['subject']} {t['task']}: {r['message']}")
        progress.update(r["status"])

    while pending:
        try:
            finished = wait(pending, timeout=5, return_when="FIRST_COMPLETED").done
        except (TimeoutError, asyncio.TimeoutError):  # nothing ended in 5 s (Dask's wait raises then)
            finished = set()
        pending.difference_update(finished)
        now = set(client.scheduler_info()["workers"])
        for lost in sorted(workers - now):
            progress.note(f"batch: worker {lost} left the cluster; its tasks run again on the others")
        workers = now
        for future in finished:
            try:
                result = future.result()
            except Exception as e:  # noqa: BLE001 - a worker lost too often (KilledWorker), a lost connection
                result = {"status": "failed", "message": f"{type(e).__name__}: {' '.join(str(e).split())}"}
            record(submitter.futures[future], result)
        for t, message in [*watch.check(pending), *timeout.check(pending)]:
            record(t, {"status": "failed", "message": message})
        if finished and time.monotonic() - last_write > 2:
            records.write_records(out_dir, _header(args, manifest, subjects, run), start)
            last_write = time.monotonic()
    progress.close()


class _StallWatch:
    """Tasks pending while the cluster has workers, all of them idle, for STALL_SECONDS were lost (a
    scheduler that forgot them): they are submitted again, up to LOST_TRIES times, then failed."""

    def __init__(self, client, submitter, progress):
        self.client, self.submitter, self.progress = client, submitter, progress
        self.idle_since = None

    def check(self, pending):
        """Updates `pending` in place; returns the (task, message) of tasks given up."""
        if not pending or any(self.client.processing().values()) or not self.client.scheduler_info()["workers"]:
            self.idle_since = None
            return []
        if self.idle_since is None:
            self.idle_since = time.monotonic()
        if time.monotonic() - self.idle_since < STALL_SECONDS:
            return []
        self.idle_since, given_up = None, []
        for future in list(pending):
            pending.discard(future)
            t = self.submitter.futures[future]
            if self.submitter.tries[t["out"]] >= LOST_TRIES:
                self.client.cancel([future])
                given_up.append((t, f"lost by the cluster {LOST_TRIES} times (every worker idle, the task pending)"))
            else:
                self.progress.note(f"batch: {t['subject']} {t['task']} was lost by the cluster (every worker idle "
                                   f"for {STALL_SECONDS} s); submitted again")
                pending.add(self.submitter.resubmit(future))
        return given_up


class _TaskTimeout:
    """A task processing on one worker for longer than `seconds` hangs there (the stall watch only sees
    idle workers): it is cancelled and recorded failed, and its worker restarted (its nanny starts a
    fresh process; any other task it held runs again elsewhere)."""

    def __init__(self, client, submitter, progress, seconds):
        self.client, self.submitter, self.progress, self.seconds = client, submitter, progress, seconds
        self.since = {}  # (task key, worker) -> when it was first seen processing there

    def check(self, pending):
        """Updates `pending` in place; returns the (task, message) of tasks stopped."""
        if not self.seconds or not pending:
            return []
        now = time.monotonic()
        processing = {(key, worker) for worker, keys in self.client.processing().items() for key in keys}
        self.since = {k: self.since.get(k, now) for k in processing}
        by_key = {f.key: f for f in pending}
        stopped, restart = [], set()
        for (key, worker), start in sorted(self.since.items(), key=lambda kv: kv[1]):
            future = by_key.get(key)
            if future is None or now - start <= self.seconds or future not in pending:
                continue
            pending.discard(future)
            self.client.cancel([future])
            restart.add(worker)
            t = self.submitter.futures[future]
            stopped.append((t, f"ran for more than {self.seconds:g} s on worker {worker} (--task-timeout): stopped, "
                               "its worker restarted"))
            self.progress.note(f"batch: {t['subject']} {t['task']} ran for more than {self.seconds:g} s; stopped and "
                               f"its worker {worker} restarted")
        if restart:
            try:
                self.client.restart_workers(sorted(restart))
            except Exception as e:  # noqa: BLE001 - no nanny (a worker started by hand): it stays busy
                self.progress.note(f"batch: could not restart {', '.join(sorted(restart))}: {' '.join(str(e).split())}")
        return stopped


def main(argv):
    try:
        args = parse_args(argv)
        manifest = load_manifest(args.manifest)
    except (UsageError, ManifestError) as e:
        print(f"repose: error: {e}", file=sys.stderr)
        return 2
    executable = os.environ.get("REPOSE_EXECUTABLE") or shutil.which("repose")
    if not executable:
        print("repose: error: run the batch as `repose batch` (the repose executable was not found)", file=sys.stderr)
        return 2
    out_dir = os.path.abspath(args.out)
    try:
        os.makedirs(out_dir, exist_ok=True)
        subjects, tasks = plan_batch(manifest, out_dir, os.environ.get("REPOSE_VERSION", "unknown"), executable)
        start, run = _run(args, manifest, subjects, tasks, out_dir, executable)
        if not args.dry_run:
            records.write_records(out_dir, _header(args, manifest, subjects, run), start)
    except KeyboardInterrupt:
        print("\nrepose: error: interrupted; complete results are kept (run again to go on)", file=sys.stderr)
        return 130
    except (OSError, RuntimeError) as e:
        print(f"repose: error: {' '.join(str(e).split())}", file=sys.stderr)
        return 1
    if args.dry_run:
        return 0
    counts = {s: sum(r["status"] == s for r in start) for s in ("done", "skipped", "failed")}
    pace = f", {run['poses_per_minute']:.1f} poses per minute" if run.get("poses_per_minute") else ""
    print(f"batch: {counts['done']} done, {counts['skipped']} complete before, {counts['failed']} failed in "
          f"{duration(run['seconds'])}{pace}; records in {out_dir}/batch.csv and batch.json")
    if counts["failed"]:
        print(f"repose: error: {out_dir}/batch.csv: {counts['failed']} of {len(start)} tasks failed "
              f"(messages there; --retry-failed runs them again)", file=sys.stderr)
        return 1
    return 0
