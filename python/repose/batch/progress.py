"""The console progress of a batch: a bar with the tasks done, failed and left and an estimate of the
time left from this run's pace. On a terminal the bar redraws in place; otherwise (a log) a line is
printed every tenth of the tasks or every 30 s."""
import sys
import time


def duration(seconds):
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds}s"
    if seconds < 3600:
        return f"{seconds // 60}m{seconds % 60:02d}s"
    return f"{seconds // 3600}h{seconds % 3600 // 60:02d}m"


class Progress:
    def __init__(self, total, stream=sys.stdout, width=30):
        self.total, self.stream, self.width = total, stream, width
        self.done = self.failed = 0
        self.t0 = self.last_print = time.monotonic()
        self.last_fraction = -1.0
        self.tty = stream.isatty()

    def line(self):
        finished = self.done + self.failed
        filled = int(self.width * finished / max(self.total, 1))
        bar = "#" * filled + "." * (self.width - filled)
        elapsed = time.monotonic() - self.t0
        left = self.total - finished
        estimate = f", about {duration(elapsed / finished * left)} left" if finished and left else ""
        return (f"batch: [{bar}] {finished}/{self.total} ({self.done} done, {self.failed} failed){estimate}, "
                f"{duration(elapsed)} so far")

    def update(self, status):
        if status == "done":
            self.done += 1
        else:
            self.failed += 1
        now, fraction = time.monotonic(), (self.done + self.failed) / max(self.total, 1)
        if self.tty:
            self.stream.write("\r" + self.line() + "\x1b[K")
        elif fraction >= 1 or fraction - self.last_fraction >= 0.1 or now - self.last_print >= 30:
            self.stream.write(self.line() + "\n")
            self.last_fraction, self.last_print = fraction, now
        self.stream.flush()

    def note(self, text):
        """A line above the bar (a failure's message)."""
        self.stream.write(("\r\x1b[K" if self.tty else "") + text + "\n")
        if self.tty:
            self.stream.write(self.line())
        self.stream.flush()

    def close(self):
        if self.tty:
            self.stream.write("\n")
            self.stream.flush()
