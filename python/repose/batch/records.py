"""The batch's record: DIR/batch.csv (one row per task) and DIR/batch.json (the exact inputs with their
hashes, the settings, the versions and every task's record), both replaced atomically as tasks end."""
import csv
import io
import json
import os
import platform

from .checked_files import sync_folder, write_text

COLUMNS = ("subject", "task", "kind", "status", "ran", "started", "finished", "seconds", "posing_seconds",
           "body_volume_ratio", "worst_bone", "worst_bone_dice", "inverted_tets", "worker", "output", "key", "message")


def _replace(path, text):
    """Writes beside `path`, checks, then renames over it: a reader sees the old file or the new one."""
    tmp = os.path.join(os.path.dirname(path), f".{os.path.basename(path)}.{os.getpid()}.tmp")
    try:
        write_text(tmp, text, path)
        os.replace(tmp, path)
    finally:
        if os.path.lexists(tmp):
            os.remove(tmp)
    sync_folder(os.path.dirname(path))


def previous_failures(out_dir):
    """{key: record} of the tasks the last run over DIR recorded as failed."""
    try:
        with open(os.path.join(out_dir, "batch.json")) as f:
            tasks = json.load(f).get("tasks", [])
    except (OSError, ValueError):
        return {}
    return {t["key"]: t for t in tasks if t.get("status") == "failed" and t.get("key")}


def versions():
    import dask
    import distributed
    from vtkmodules.vtkCommonCore import vtkVersion
    return {"repose": os.environ.get("REPOSE_VERSION", "unknown"), "python": platform.python_version(),
            "vtk": vtkVersion.GetVTKVersion(), "dask": dask.__version__, "distributed": distributed.__version__}


def csv_text(records):
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(COLUMNS)
    for r in records:
        row = dict(r, output=r.get("out", ""))
        writer.writerow(["" if row.get(c) is None else row.get(c, "") for c in COLUMNS])
    return out.getvalue()


def write_records(out_dir, header, records):
    """Rewrites DIR/batch.csv and DIR/batch.json (header: manifest, subjects, settings, run)."""
    _replace(os.path.join(out_dir, "batch.csv"), csv_text(records))
    _replace(os.path.join(out_dir, "batch.json"), json.dumps({**header, "tasks": records}, indent=2) + "\n")
