#pragma once
// Ctrl-C or a kill during a command leaves nothing behind. SIGINT, SIGTERM and SIGHUP are caught by
// a handler that only writes the signal's number into a pipe (async-signal-safe, and any thread may
// receive it: libraries start threads before main); a thread of its own reads the pipe, removes the
// temporary folders of the outputs being written, prints one line and exits 128 + the signal
// number (130 for SIGINT, 143 for SIGTERM). A signal ignored when the program starts (nohup, a
// background job of a script) stays ignored.

namespace repose {

/// Call once, first in main.
void cleanUpOnInterrupt();

}  // namespace repose
