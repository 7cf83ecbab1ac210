"""Result folders written atomically: a task writes into a hidden folder beside its result and renames
it into place when everything is in it, with RESULT_FILE (its key, figures and times) inside. A folder
under the final name is therefore complete, and complete for the inputs its key names. Every file in it
is checked and on the disk before the rename (checked_files), and the rename itself is flushed."""
import json
import os
import shutil
import uuid

from .checked_files import check_written, sync_folder, write_text

RESULT_FILE = "batch_task.json"


def staging_dir(final_dir):
    """A fresh hidden folder beside `final_dir` (same file system, so the rename is atomic)."""
    parent, name = os.path.split(final_dir.rstrip("/"))
    os.makedirs(parent, exist_ok=True)
    path = os.path.join(parent, f".{name}.part-{uuid.uuid4().hex[:12]}")
    os.makedirs(path)
    return path


def publish(staging, final_dir, record):
    """Writes the record into `staging` and moves it to `final_dir`, replacing an older result."""
    write_text(os.path.join(staging, RESULT_FILE), json.dumps(record, indent=2, sort_keys=True) + "\n")
    check_written(staging, final_dir)  # every file, its companions too, complete and flushed
    old = None
    if os.path.lexists(final_dir):
        old = staging + ".old"
        os.rename(final_dir, old)
    os.rename(staging, final_dir)
    sync_folder(os.path.dirname(final_dir.rstrip("/")))
    if old:
        shutil.rmtree(old, ignore_errors=True)


def final_paths(message, staging, final_dir):
    """A message with the staging folder's paths turned into the final folder's (the files the user sees)."""
    return message.replace(staging, final_dir.rstrip("/")) if staging else message


def sweep(root):
    """Removes the hidden staging folders under `root` (left by workers killed mid-task); call it only
    when no task writing under `root` is running."""
    for folder, subfolders, _files in os.walk(root):
        for name in list(subfolders):
            if name.startswith(".") and ".part-" in name:
                shutil.rmtree(os.path.join(folder, name), ignore_errors=True)
                subfolders.remove(name)


def discard(staging):
    shutil.rmtree(staging, ignore_errors=True)


def completed(final_dir, key):
    """The record of a complete result for `key`, or None (missing, other inputs, or a file gone)."""
    try:
        with open(os.path.join(final_dir, RESULT_FILE)) as f:
            record = json.load(f)
    except (OSError, ValueError):
        return None
    if record.get("key") != key or record.get("status") != "done":
        return None
    if not all(os.path.exists(os.path.join(final_dir, name)) for name in record.get("files", [])):  # a DICOM series is a folder
        return None
    return record
