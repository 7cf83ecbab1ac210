"""What a Dask worker runs: prepare a subject (once) and pose one pose or clip frame. Each task
returns a record (status, times, figures, message) instead of raising, so one failure is reported
and the others go on; its result folder appears complete or not at all (store.py)."""
import os
import shutil
import socket
import subprocess
import threading
import time
import traceback
from datetime import datetime, timezone

from . import store
from .checked_files import write_text
from .manifest import PREPARE_OPTIONS

_local = threading.local()  # per worker thread: the case it has loaded (tasks of a thread run one at a time)
_threads_set = []


def _now():
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds")


def _record(task):
    return {"kind": task["kind"], "subject": task["subject"], "task": task["task"], "key": task["key"],
            "out": task["out"], "status": "failed", "started": _now(), "worker": f"{socket.gethostname()}:{os.getpid()}",
            "message": ""}


def _finish(record, t0):
    record["finished"] = _now()
    record["seconds"] = round(time.perf_counter() - t0, 4)
    return record


def _one_line(text):
    return " ".join(str(text).split())


def prepare_command(task, out):
    cmd = [task["executable"], "prepare", "--labels", task["labels"], "--skeleton", task["skeleton"], "--out", out]
    if task["image"]:
        cmd += ["--image", task["image"]]
    if task["label_table"]:
        cmd += ["--label-table", task["label_table"]]
    for key, value in sorted(task["prepare"].items()):
        cmd += [PREPARE_OPTIONS[key], repr(value) if isinstance(value, float) else str(value)]
    return cmd


def _dying_with_worker(cmd):
    """The command run so that it is killed when its worker dies (Linux's parent-death signal, set by
    util-linux's setpriv): not left preparing alone. Not by a preexec_fn, which runs Python between
    fork and exec in a threaded worker and can deadlock there (on the import lock)."""
    setpriv = shutil.which("setpriv")
    return [setpriv, "--pdeathsig", "KILL", "--", *cmd] if setpriv else cmd


def prepare_subject(task):
    """`repose prepare` of one subject into its case folder (the command's own checks, label table
    and automatic rig apply); the folder is renamed into place with its record when complete."""
    done = store.completed(task["out"], task["key"])
    if done:  # Dask runs it again when the worker holding its result was lost: keep the case others read
        return done
    t0, record = time.perf_counter(), _record(task)
    staging = store.staging_dir(task["out"])
    try:
        cmd = prepare_command(task, staging)
        p = subprocess.run(_dying_with_worker(cmd), capture_output=True, text=True)
        write_text(os.path.join(staging, "prepare.log"), " ".join(cmd) + "\n" + p.stdout + p.stderr)
        if p.returncode != 0:
            lines = [line for line in p.stderr.splitlines() if line.strip()] or [f"exit code {p.returncode}"]
            raise RuntimeError(lines[-1].replace("repose: error: ", "", 1))
        record.update(status="done", files=sorted(os.listdir(staging)), command=cmd)
        store.publish(staging, task["out"], _finish(record, t0))
    except Exception as e:  # noqa: BLE001 - every failure becomes the task's message
        store.discard(staging)
        record["message"] = store.final_paths(_one_line(e), staging, task["out"])
        _finish(record, t0)
    return record


def _poser(task):
    """The worker thread's CasePoser for the task's case, loaded once (and its figures' rest data)."""
    from .metrics import RestFigures
    from .posing import CasePoser
    image = task["image"] if "image" in task["outputs"] else None
    wanted = (task["case"], task["case_key"], image)
    if getattr(_local, "key", None) != wanted:
        _local.key, _local.poser = None, None  # free the previous case first
        poser = CasePoser(task["case"], image)
        poser.figures = RestFigures(poser.rest_mesh, poser.rest_labels, poser.skeleton_json)
        _local.poser, _local.key = poser, wanted
    return _local.poser


def _set_threads(count):
    """Threads of the filters (vtkSMPTools) in this worker process: cores shared among the workers."""
    if count and not _threads_set:
        from vtkmodules.vtkCommonCore import vtkSMPTools
        vtkSMPTools.Initialize(count)
        _threads_set.append(count)


def pose_task(prepared, task):
    """Poses one pose file (kind "pose") or BVH frame (kind "frame") of a prepared subject."""
    done = store.completed(task["out"], task["key"])
    if done:  # run again after a lost worker: its result is already in place
        return done
    t0, record = time.perf_counter(), _record(task)
    if prepared["status"] != "done":
        record["message"] = f"subject {task['subject']} was not prepared: {prepared['message']}"
        return _finish(record, t0)
    staging = None
    try:
        _set_threads(task.get("threads"))
        poser = _poser(task)
        if task["kind"] == "frame":
            pose_json = poser.frame_text(task["bvh"], task["map"], task["retarget"], task["frame"])
        else:
            pose_json = poser.pose_text(task["pose_file"], task["pose_text"])
        staging = store.staging_dir(task["out"])
        t1 = time.perf_counter()
        poser.configure(task["skinning"], task["relax"])
        posed = poser.pose(pose_json, task["outputs"])
        record["posing_seconds"] = round(time.perf_counter() - t1, 4)
        record["files"] = poser.write(posed, task["outputs"], task["format"], staging)
        record.update(poser.figures.figures(posed["mesh"], posed["labels"]))
        if task["kind"] == "frame":
            write_text(os.path.join(staging, "pose.json"), pose_json)
            record["files"].append("pose.json")
        record["status"] = "done"
        store.publish(staging, task["out"], _finish(record, t0))
    except Exception as e:  # noqa: BLE001 - every failure becomes the task's message
        if staging:
            store.discard(staging)
        message = _one_line(e) or _one_line(traceback.format_exc().splitlines()[-1])
        record["message"] = store.final_paths(message, staging, task["out"])
        _finish(record, t0)
    return record
