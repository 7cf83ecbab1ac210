#pragma once
// `repose batch`: hands the command line to the Python batch runner (python/repose/batch), which
// runs many subjects x poses on Dask through the Python-wrapped filters.

namespace repose {

/// Replaces this process with the Python runner (`python3 -m repose.batch ARGS...`, the package
/// found beside this executable); returns only on failure, throwing std::runtime_error.
[[noreturn]] void execBatchRunner(int argc, char** argv, int first);

}  // namespace repose
