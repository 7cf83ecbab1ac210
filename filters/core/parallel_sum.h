#pragma once
// Sums over [0, n) on parallelFor() whose bits do not depend on the thread count or the runner:
// the range is cut into chunks that depend only on n and the chunk size, each chunk is summed into
// its own partial, and the partials are added in chunk order. (A reduction split by thread rounds
// differently on 1 and 2 threads, and CG's iterates, its iteration count and through them a
// relaxation's line-search decisions follow those last bits.)
#include <cstddef>
#include <functional>

namespace repose {

/// Adds the contributions of [begin, end) to partial[0, width), which starts at zero.
using ChunkSumBody = std::function<void(std::size_t begin, std::size_t end, double* partial)>;

/// result[0, width) = the sums over [0, n) of body's contributions, taken per chunk of `chunk`
/// indices (the last one shorter) and then in chunk order. width may be large (e.g. a coarse vector):
/// the partials are then added in parallel over the width, each entry still in chunk order.
void parallelSums(std::size_t n, std::size_t chunk, std::size_t width, const ChunkSumBody& body, double* result);

/// One sum: body(begin, end) returns the sum over [begin, end).
double parallelSum(std::size_t n, std::size_t chunk, const std::function<double(std::size_t, std::size_t)>& body);

}  // namespace repose
