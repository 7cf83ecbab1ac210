"""repose batch on Dask: the tiny phantom (3 poses, one of them again under another name, a pose
naming an unknown joint, 3 CMU frames), the small phantom (3 poses) and the TotalSegmentator CT (3
poses, CT posed too) on a local cluster of 2 workers, one of them killed mid-run; every posed file equals `repose pose`'s (and
`repose animate`'s for a frame) byte for byte; a rerun skips everything; --retry-failed on an existing
scheduler runs the failure again."""
import csv
import filecmp
import hashlib
import json
import os
import shutil
import subprocess
import sys
import time

import psutil

from repose_testing import EXE, SHARED, TEMP, TESTING, check, run

failures = []
work = os.path.join(TEMP, "batch")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(os.path.join(work, "poses"))
out = os.path.join(work, "out")
run("phantom", "--out", os.path.join(work, "tiny"), "--size", "tiny")
run("phantom", "--out", os.path.join(work, "small"), "--size", "small")
ts = os.path.join(SHARED, "totalsegmentator")
ct = os.path.join(ts, "example_ct.nii.gz")
bvh = os.path.join(SHARED, "mocap", "cmu_short_75frames.bvh")


def pose_file(name, rotations):
    path = os.path.join(work, "poses", name + ".json")
    with open(path, "w") as f:
        json.dump({"rotations": {j: {"axis": a, "degrees": d} for j, (a, d) in rotations.items()}}, f, indent=2)
    return path


tiny_poses = {"hip": pose_file("hip", {"left_hip": ([1, 0, 0], -45)}),
              "arm": pose_file("arm", {"right_shoulder": ([0, 1, 0], 60), "right_elbow": ([1, 0, 0], -80)}),
              "knee": pose_file("knee", {"left_knee": ([1, 0, 0], 40), "right_hip": ([1, 0, 0], -20)})}
tiny_poses["hip_again"] = tiny_poses["hip"]  # the same result under two names (the same task key)
bad = pose_file("tail", {"left_tail": ([1, 0, 0], 30)})
ts_poses = {"hip_flexion": os.path.join(TESTING, "Data", "totalsegmentator_hip_flexion.json"),
            "abduction": pose_file("abduction", {"right_hip": ([0, 1, 0], -15)}),
            "spine": pose_file("spine", {"lumbar_spine": ([1, 0, 0], 10)})}
small_poses = {n: tiny_poses[n] for n in ("hip", "arm", "knee")}
TASKS = 3 + len(tiny_poses) + 1 + 3 + len(small_poses) + len(ts_poses)  # prepares, tiny poses and its failing one, frames, small's and the CT's poses
manifest = os.path.join(work, "batch.json")
with open(manifest, "w") as f:
    json.dump({"settings": {"outputs": ["labels", "mesh", "surfaces", "image"]},
               "subjects": [
                   {"name": "tiny", "labels": "tiny/labels.nii.gz", "skeleton": "tiny/skeleton.json",
                    "poses": [*({"name": n, "file": f} for n, f in tiny_poses.items()), bad], "clips": [{"file": bvh, "frames": "0:75:37"}]},
                   {"name": "small", "labels": "small/labels.nii.gz", "skeleton": "small/skeleton.json",
                    "poses": [{"name": n, "file": f} for n, f in small_poses.items()]},
                   {"name": "totalseg", "labels": os.path.join(ts, "example_seg_fast_force_split.nii.gz"),
                    "image": ct, "skeleton": os.path.join(TESTING, "Data", "totalsegmentator_skeleton.json"),
                    "prepare": {"mesh_spacing": 6}, "poses": [{"name": n, "file": f} for n, f in ts_poses.items()]}]},
              f, indent=2)


def batch(*args):
    p = subprocess.run([EXE, "batch", manifest, "--out", out, *args], capture_output=True, text=True)
    print(p.stdout + p.stderr)
    return p


def rows():
    with open(os.path.join(out, "batch.csv")) as f:
        return {(r["subject"], r["task"]): r for r in csv.DictReader(f)}


# --- a local cluster of 2 workers; one is killed once the first pose is written ----------------------
t0 = time.monotonic()
proc = subprocess.Popen([EXE, "batch", manifest, "--out", out, "--workers", "2"], stdout=subprocess.PIPE,
                        stderr=subprocess.STDOUT, text=True)
BATCH_SECONDS = 600  # about 50 s here; a batch that loses a worker must end, not hang
killed, left_at_kill = None, 0
while proc.poll() is None and killed is None and time.monotonic() - t0 < BATCH_SECONDS:
    time.sleep(0.2)
    written = [d for d in ("hip", "arm", "knee") if os.path.isfile(os.path.join(out, "tiny", "poses", d, "batch_task.json"))]
    if not written:
        continue
    workers = [c for c in psutil.Process(proc.pid).children() if "spawn_main" in " ".join(c.cmdline())]
    # The worker that is posing (not the one running the TotalSegmentator prepare), if both are there.
    posing = [w for w in workers if not any("prepare" in " ".join(c.cmdline()) for c in w.children())]
    if len(workers) == 2 and posing:
        killed = posing[0].pid
        posing[0].kill()
        left_at_kill = TASKS - 1 - sum("batch_task.json" in files for _, _, files in os.walk(out))
try:
    log, _ = proc.communicate(timeout=max(1.0, BATCH_SECONDS - (time.monotonic() - t0)))
except subprocess.TimeoutExpired:
    for c in [*psutil.Process(proc.pid).children(recursive=True), proc]:  # its workers hold the pipe too
        c.kill()
    log, _ = proc.communicate()
    print(log)
    print(f"FAIL: the batch that lost a worker did not end in {BATCH_SECONDS} s (killed)")
    sys.exit(1)
print(log)
first_run = time.monotonic() - t0
check(killed is not None and left_at_kill > 0,
      f"a worker (pid {killed}) was killed mid-run, with {left_at_kill} of {TASKS - 1} tasks not yet written", failures)
check(proc.returncode == 1 and "tail" in log and "unknown joint 'left_tail'" in log
      and not os.path.exists(os.path.join(out, "tiny", "poses", "tail")),
      f"the pose naming an unknown joint is reported with its message, no output (exit {proc.returncode})", failures)
r = rows()
good = [k for k in r if k != ("tiny", "tail")]
check(len(r) == TASKS and all(r[k]["status"] == "done" for k in good) and r[("tiny", "tail")]["status"] == "failed",
      f"first run ({first_run:.0f} s): {sum(v['status'] == 'done' for v in r.values())} of {TASKS} tasks done, "
      f"the failing one recorded: {r[('tiny', 'tail')]['message'][:60]}...", failures)
check(not any(".part-" in d for _, dirs, _ in os.walk(out) for d in dirs),
      "no half-written folder is left behind by the killed worker", failures)
posed = [v for k, v in r.items() if v["kind"] in ("pose", "frame") and v["status"] == "done"]
ratios = [float(v["body_volume_ratio"]) for v in posed]
dice = [float(v["worst_bone_dice"]) for v in posed]
check(all(0.97 < x < 1.03 for x in ratios) and all(d >= 0.9 for d in dice) and all(v["inverted_tets"].isdigit() for v in posed),
      f"figures: body volume ratio {min(ratios):.4f}-{max(ratios):.4f}, worst bone Dice >= {min(dice):.3f}", failures)

# --- every posed file equals the CLI's ---------------------------------------------------------------------
different = []
for subject, poses, extra in (("tiny", tiny_poses, []), ("small", small_poses, []), ("totalseg", ts_poses, ["--image", ct])):
    for name, path in poses.items():
        ref = os.path.join(work, "ref", subject, name)
        run("pose", "--case", os.path.join(out, subject, "case"), "--pose", path, *extra, "--out", ref)
        mine = os.path.join(out, subject, "poses", name)
        for f in os.listdir(ref):
            if not filecmp.cmp(os.path.join(ref, f), os.path.join(mine, f), shallow=False):
                different.append(f"{subject}/{name}/{f}")
check(not different and os.path.isfile(os.path.join(out, "totalseg", "poses", "spine", "posed_image.nii.gz")),
      f"{len(tiny_poses) + len(small_poses) + len(ts_poses)} poses: labels, mesh, surfaces (and CT) equal repose pose's byte for byte "
      f"{different}", failures)
ref = os.path.join(work, "ref", "animate")
run("animate", "--case", os.path.join(out, "tiny", "case"), "--bvh", bvh, "--frames", "37:38", "--volumes", "--out", ref)
frame = os.path.join(out, "tiny", "clips", "cmu_short_75frames", "frame_00037")
same = all(filecmp.cmp(os.path.join(ref, "frames", a), os.path.join(frame, b), shallow=False) for a, b in
           (("mesh_00037.vtu", "posed_mesh.vtu"), ("surfaces_00037.vtp", "posed_surfaces.vtp"),
            ("labels_00037.nii.gz", "posed_labels.nii.gz")))
check(same, "BVH frame 37 equals repose animate's frame 37 byte for byte", failures)

# --- the record: exact inputs with their hashes, version ---------------------------------------------------
with open(os.path.join(out, "batch.json")) as f:
    record = json.load(f)
with open(ct, "rb") as f:
    ct_hash = hashlib.sha256(f.read()).hexdigest()
version = run("--version")[1].split()[1]
check(record["versions"]["repose"] == version and record["subjects"][2]["inputs"]["image"]["sha256"] == ct_hash
      and record["settings"]["workers"] == 2,
      f"batch.json: repose {record['versions']['repose']}, the CT's sha256, 2 workers", failures)

# --- a rerun skips everything ------------------------------------------------------------------------------
stamp = os.path.getmtime(os.path.join(out, "totalseg", "poses", "spine", "posed_labels.nii.gz"))
t0 = time.monotonic()
p = batch()
r = rows()
check(p.returncode == 1 and all(r[k]["status"] == "skipped" for k in good) and r[("tiny", "tail")]["ran"] == "earlier"
      and os.path.getmtime(os.path.join(out, "totalseg", "poses", "spine", "posed_labels.nii.gz")) == stamp,
      f"a rerun skips all {TASKS - 1} complete tasks and the earlier failure ({time.monotonic() - t0:.1f} s)", failures)

# --- --retry-failed on an existing cluster (a scheduler and one worker started here) -----------------------
scheduler_file = os.path.join(work, "scheduler.json")
env = dict(os.environ)
dask = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                          "--port", "0", "--dashboard-address", ":0", "--scheduler-file", scheduler_file],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
try:
    for _ in range(200):
        if os.path.isfile(scheduler_file) and os.path.getsize(scheduler_file):
            break
        time.sleep(0.1)
    with open(scheduler_file) as f:
        address = json.load(f)["address"]
    dask.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                                  "--nworkers", "1"], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    started_before = r[("tiny", "tail")]["started"]
    p = batch("--retry-failed", "--scheduler", address)
    r = rows()
    check(p.returncode == 1 and r[("tiny", "tail")]["ran"] == "this" and r[("tiny", "tail")]["started"] != started_before
          and all(r[k]["status"] == "skipped" for k in good) and "1 worker on " + address in p.stdout,
          "--retry-failed on an existing scheduler runs the failed task again (and only it)", failures)
finally:
    for d in reversed(dask):
        d.terminate()
        d.wait(timeout=30)

p = subprocess.run([EXE, "batch", os.path.join(work, "poses", "hip.json"), "--out", out], capture_output=True, text=True)
check(p.returncode == 2 and p.stderr.startswith("repose: error: ") and p.stderr.count("\n") == 1 and "subjects" in p.stderr,
      f"a file that is no manifest: one line, exit 2 ({p.stderr.strip()})", failures)
print(f"{len(failures)} check(s) failed" if failures else "all checks passed")
sys.exit(1 if failures else 0)
