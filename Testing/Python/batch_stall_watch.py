"""The batch's stall watch against a scripted cluster: tasks pending while every worker is idle for
STALL_SECONDS are submitted again under new keys, at most LOST_TRIES times, then given up with a message;
nothing happens while a worker is busy or while the cluster has no worker. And its task timeout: a task
processing on one worker longer than --task-timeout is cancelled, recorded failed and its worker
restarted; a task that moved to another worker starts its clock again; 0 means no limit."""
import sys

from repose.batch import runner

from repose_testing import check

failures = []


class Cluster:
    """What the watch asks of a Dask client: which workers exist and what each is processing."""

    def __init__(self):
        self.workers, self.busy, self.cancelled = {"tcp://w1": {}}, False, []

    def processing(self):
        return {w: (["a-task"] if self.busy else []) for w in self.workers}

    def scheduler_info(self):
        return {"workers": self.workers}

    def cancel(self, futures):
        self.cancelled += futures


class Submitter:
    """The runner's submitter, keeping its contract: futures -> task, tries per task, resubmit."""

    def __init__(self):
        self.futures, self.tries = {}, {}

    def submit(self, task):
        future = object()
        self.futures[future] = task
        self.tries[task["out"]] = self.tries.get(task["out"], 0) + 1
        return future

    def resubmit(self, future):
        return self.submit(self.futures.pop(future))


clock = [1000.0]
runner.time.monotonic = lambda: clock[0]  # the watch's time, advanced by hand
cluster, submitter = Cluster(), Submitter()
task = {"subject": "tiny", "task": "hip", "out": "tiny/poses/hip"}
pending = {submitter.submit(task)}
watch = runner._StallWatch(cluster, submitter, type("Quiet", (), {"note": lambda self, text: None})())

first = set(pending)
check(watch.check(pending) == [] and pending == first, "idle for 0 s: nothing done", failures)
clock[0] += runner.STALL_SECONDS - 1
check(watch.check(pending) == [] and pending == first, f"idle for {runner.STALL_SECONDS - 1} s: nothing done", failures)
cluster.busy = True
clock[0] += 10
check(watch.check(pending) == [] and pending == first, "a busy worker resets the watch", failures)
cluster.busy = False
watch.check(pending)
clock[0] += runner.STALL_SECONDS
given_up = watch.check(pending)
check(given_up == [] and len(pending) == 1 and pending != first and submitter.tries[task["out"]] == 2,
      f"idle for {runner.STALL_SECONDS} s: the task is submitted again under a new future", failures)
cluster.workers = {}
clock[0] += 10 * runner.STALL_SECONDS
check(watch.check(pending) == [] and submitter.tries[task["out"]] == 2, "no worker at all: the watch waits", failures)
cluster.workers = {"tcp://w2": {}}
for _ in range(runner.LOST_TRIES):
    watch.check(pending)
    clock[0] += runner.STALL_SECONDS
    given_up = watch.check(pending)
    if given_up:
        break
check(len(given_up) == 1 and given_up[0][0] is task and "lost by the cluster" in given_up[0][1] and not pending
      and submitter.tries[task["out"]] == runner.LOST_TRIES and len(cluster.cancelled) == 1,
      f"after {runner.LOST_TRIES} submissions the task is given up: {given_up[0][1] if given_up else None}", failures)

# --- the task timeout: a task hanging inside a busy worker ------------------------------------------------
class Future:
    def __init__(self, key):
        self.key = key


class BusyCluster(Cluster):
    def __init__(self):
        super().__init__()
        self.running, self.restarted = {}, []  # worker -> keys

    def processing(self):
        return {w: self.running.get(w, []) for w in self.workers}

    def restart_workers(self, workers):
        self.restarted += workers


busy, submitter2 = BusyCluster(), Submitter()
hung, quick = Future("pose-hip"), Future("pose-arm")
submitter2.futures = {hung: {"subject": "tiny", "task": "hip", "out": "a"}, quick: {"subject": "tiny", "task": "arm", "out": "b"}}
quiet = type("Quiet", (), {"note": lambda self, text: None})()
limit = runner._TaskTimeout(busy, submitter2, quiet, 600)
pending = {hung, quick}
busy.running = {"tcp://w1": ["pose-hip"], "tcp://w2": ["pose-arm"]}
check(limit.check(pending) == [] and pending == {hung, quick}, "tasks start processing: nothing done", failures)
clock[0] += 400
busy.running = {"tcp://w1": ["pose-hip"], "tcp://w3": ["pose-arm"]}  # the quick one moved: its clock restarts
check(limit.check(pending) == [] and pending == {hung, quick}, "400 s in: nothing done", failures)
clock[0] += 300
stopped = limit.check(pending)
check(len(stopped) == 1 and stopped[0][0]["task"] == "hip" and "--task-timeout" in stopped[0][1] and pending == {quick}
      and busy.cancelled[-1:] == [hung] and busy.restarted == ["tcp://w1"],
      f"700 s on one worker (limit 600 s): stopped, its worker restarted: {stopped[0][1] if stopped else None}", failures)
clock[0] += 550
check(limit.check(pending) == [] and pending == {quick}, "a task that moved worker counts from its move", failures)
no_limit = runner._TaskTimeout(busy, submitter2, quiet, 0)
clock[0] += 10 ** 6
check(no_limit.check(pending) == [] and pending == {quick}, "--task-timeout 0: no limit", failures)
print(f"{len(failures)} check(s) failed" if failures else "all checks passed")
sys.exit(1 if failures else 0)
