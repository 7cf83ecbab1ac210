"""Interrupted runs leave nothing: SIGINT or SIGTERM during animate, pose (in its FEM relaxation, with
its temporary folder open) and prepare (while meshing) exit 130 or 143 with one line, and remove the
temporary folder and the output folder they created; inputs stay byte-identical. A run killed with
SIGKILL cannot clean up: the next run into the same folder removes its stale .repose-tmp-<pid>
folder. Staleness is decided by the folder's lock, not by its pid: a folder whose pid now belongs to
another live process is removed when nobody holds its lock, and one locked by a live process is kept
(a run in another pid namespace or on another host of a network file system), as is an image writer's
locked temporary folder."""
import fcntl
import os
import shutil
import signal
import subprocess
import sys
import time

from repose_testing import EXE, SHARED, TEMP, TESTING, TINY, check, file_hashes, run

work = os.path.join(TEMP, "interrupted_outputs")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []
phantom, case = f"{TINY}/phantom", f"{TINY}/case"
pose = os.path.join(TESTING, "Data", "tiny_pose.json")
bvh = os.path.join(SHARED, "mocap", "cmu_131_01_walk.bvh")  # 994 frames: long enough to interrupt
inputs = [phantom, case, pose, bvh]
before = file_hashes(*inputs)


def temporary_folders(folder):
    return [n for n in os.listdir(folder) if n.startswith(".repose-tmp-")] if os.path.isdir(folder) else []


def start(args):
    return subprocess.Popen([EXE, *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def wait_for_outputs(p, folder, timeout=120):
    """Waits until the run has a temporary folder with something in it; False if it ended first."""
    t0 = time.time()
    while time.time() - t0 < timeout and p.poll() is None:
        for name in temporary_folders(folder):
            if os.listdir(os.path.join(folder, name)):
                return True
        time.sleep(0.02)
    return False


runs = [
    ("animate", ["animate", "--case", case, "--bvh", bvh, "--out"], signal.SIGINT, True),
    ("animate", ["animate", "--case", case, "--bvh", bvh, "--out"], signal.SIGTERM, True),
    ("pose --relax", ["pose", "--case", case, "--pose", pose, "--relax", "--out"], signal.SIGINT, True),
    ("prepare", ["prepare", "--labels", f"{phantom}/labels.nii.gz", "--skeleton", f"{phantom}/skeleton.json",
                 "--out"], signal.SIGTERM, False),
]
for name, args, sig, has_outputs in runs:
    what = f"{name} interrupted by {sig.name}"
    out = f"{work}/out/{name.split()[0]}"
    p = start(args + [out])
    if has_outputs:
        # the run is writing: its temporary folder holds a file
        check(wait_for_outputs(p, out) or os.path.isdir(out), f"{what}: temporary folder seen", failures)
    else:
        time.sleep(1.5)  # meshing: no output folder yet
    p.send_signal(sig)
    err = p.communicate(timeout=60)[1].strip()
    check(p.returncode == 128 + sig, f"{what}: exit {128 + sig} (got {p.returncode})", failures)
    check(len(err.splitlines()) == 1 and err.startswith(f"repose: error: {out}: interrupted by {sig.name}"),
          f"{what}: one line naming {out} ({err!r})", failures)
    check(not os.path.exists(out), f"{what}: no output folder left", failures)
    shutil.rmtree(f"{work}/out", ignore_errors=True)

# A run killed outright leaves its temporary folder; the next run into the folder removes it.
out = f"{work}/killed"
p = start(["animate", "--case", case, "--bvh", bvh, "--out", out])
check(wait_for_outputs(p, out), "animate started writing before SIGKILL", failures)
p.kill()
p.wait()
stale = temporary_folders(out)
check(len(stale) == 1 and stale[0] == f".repose-tmp-{p.pid}", f"SIGKILL leaves {stale}", failures)
live = subprocess.Popen(["sleep", "60"])
os.makedirs(f"{out}/.repose-tmp-{live.pid}/frames")  # its pid given to a live process, but unlocked: removed
locks = []
for locked in (f"{out}/.repose-tmp-999999999",  # no such pid here, but its lock is held: kept
               f"{out}/.repose-tmp-{os.getpid()}-labels.nii.gz.d"):  # a live image writer's: kept
    os.makedirs(locked)
    locks.append(os.open(locked, os.O_RDONLY))
    fcntl.flock(locks[-1], fcntl.LOCK_EX)
with open(f"{out}/.repose-tmp-{p.pid}-labels.nii.gz", "wb") as f:  # an older image writer's temporary file
    f.write(b"partial")
code, _, err = run("phantom", "--size", "tiny", "--out", out, check=False)
left = sorted(temporary_folders(out))
check(code == 0, f"the next run succeeds ({err.strip()})", failures)
check(left == sorted([".repose-tmp-999999999", f".repose-tmp-{os.getpid()}-labels.nii.gz.d"]),
      f"stale folders and file removed (one with a live process's pid), locked ones kept ({left})", failures)
live.kill()
live.wait()
for lock in locks:
    os.close(lock)
code, _, err = run("phantom", "--size", "tiny", "--out", out, check=False)
check(code == 0 and temporary_folders(out) == [], f"once dead and unlocked, they go too ({temporary_folders(out)})",
      failures)
check(file_hashes(*inputs) == before, "inputs byte-identical", failures)
total = 4 * len(runs) + 5
print(f"{total - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
