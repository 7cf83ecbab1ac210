"""repose batch on a full disk: the tiny phantom is prepared and posed once with room, then its pose runs
again under file-size limits (RLIMIT_FSIZE, so that a write fails with EFBIG as it does with ENOSPC on a
full file system) that cut one output short. Each time the task fails with one line naming the final
file and the reason, no result folder nor staging folder is left, the prepared case is untouched, and
the exit code is 1. A limit the batch's own records (batch.csv) do not fit in is one error line that
names batch.csv, the previous records left whole. With room again the pose is done."""
import csv
import json
import os
import shutil
import subprocess
import sys

from repose_testing import EXE, TEMP, TINY, check, file_hashes

failures = []
work = os.path.join(TEMP, "batch_full_disk")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
out, manifest = os.path.join(work, "out"), os.path.join(work, "batch.json")
pose = os.path.join(work, "hip.json")
with open(pose, "w") as f:
    json.dump({"rotations": {"left_hip": {"axis": [1, 0, 0], "degrees": -45}}}, f)
phantom = os.path.join(TINY, "phantom")
inputs = [os.path.join(phantom, "labels.nii.gz"), os.path.join(phantom, "skeleton.json"), pose]
before = file_hashes(*inputs)
KB, MB = 1024, 1024 * 1024
result = os.path.join(out, "tiny", "poses", "hip")


def batch(outputs, limit=None):
    """`repose batch` of the phantom's one pose writing `outputs`, under a file-size limit if given."""
    with open(manifest, "w") as f:
        json.dump({"settings": {"outputs": outputs},
                   "subjects": [{"name": "tiny", "labels": inputs[0], "skeleton": inputs[1],
                                 "poses": [{"name": "hip", "file": pose}]}]}, f)
    limited = ["prlimit", f"--fsize={limit}"] if limit else []
    p = subprocess.run([*limited, EXE, "batch", manifest, "--out", out, "--workers", "1", "--retry-failed"],
                       capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr, p.stderr


def records():
    with open(os.path.join(out, "batch.csv")) as f:
        return {r["task"]: r for r in csv.DictReader(f)}


code, log, _ = batch(["labels", "mesh", "surfaces"])
check(code == 0 and records()["hip"]["status"] == "done", f"with room the pose is done (exit {code})", failures)
case = file_hashes(os.path.join(out, "tiny", "case"))
sizes = {n: os.path.getsize(os.path.join(result, n)) for n in os.listdir(result)}
print("outputs:", ", ".join(f"{n} {s} B" for n, s in sorted(sizes.items())))

# (outputs, limit, the file the message names): the mesh cut near its start and near its end, the
# surfaces, and the gzip label volume (written by vtkReposeImageWriter, its staging path renamed).
runs = [(["labels", "mesh", "surfaces"], 20 * KB, "posed_mesh.vtu"),
        (["mesh"], sizes["posed_mesh.vtu"] - 100, "posed_mesh.vtu"),
        (["surfaces"], 1 * MB, "posed_surfaces.vtp"),
        (["labels"], 8 * KB, "posed_labels.nii.gz")]
for outputs, limit, named in runs:
    shutil.rmtree(result, ignore_errors=True)
    what = f"{'+'.join(outputs)} under a {limit} B file-size limit"
    code, log, err = batch(outputs, limit)
    message = f"{os.path.join(result, named)}: cannot write (file too large)"
    failed = [line for line in log.splitlines() if line.startswith("batch: failed:")]
    check(code == 1 and failed == [f"batch: failed: tiny hip: {message}"],
          f"{what}: exit 1 (got {code}), one line naming the file: {failed}", failures)
    check(records()["hip"]["status"] == "failed" and records()["hip"]["message"] == message,
          f"{what}: the task's record has the message", failures)
    left = [os.path.join(d, n) for d, dirs, files in os.walk(out) for n in dirs + files if ".part-" in n]
    check(not os.path.exists(result) and not left, f"{what}: no result folder, no staging folder left {left}", failures)
    check(file_hashes(os.path.join(out, "tiny", "case")) == case, f"{what}: the prepared case is untouched", failures)

# The batch's own records: the previous batch.csv stays whole, the error names it.
shutil.rmtree(result, ignore_errors=True)
with open(os.path.join(out, "batch.csv")) as f:
    previous = f.read()
code, log, err = batch(["labels"], len(previous) - 10)
lines = err.strip().splitlines()
check(code == 1 and lines[-1:] == [f"repose: error: {out}/batch.csv: cannot write (file too large)"],
      f"records under a {len(previous) - 10} B limit: exit 1 (got {code}), {lines[-1:]}", failures)
with open(os.path.join(out, "batch.csv")) as f:
    check(f.read() == previous, "the previous batch.csv is left whole", failures)
check(not [n for n in os.listdir(out) if n.endswith(".tmp")], "no temporary records left", failures)

code, log, _ = batch(["labels", "mesh", "surfaces"], 64 * MB)
check(code == 0 and records()["hip"]["status"] == "done" and sorted(os.listdir(result)) == sorted(sizes),
      f"with room under a 64 MB limit the pose is done again (exit {code})", failures)
check(file_hashes(*inputs) == before, "inputs byte-identical", failures)
print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
