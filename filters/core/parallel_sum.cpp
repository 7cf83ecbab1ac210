#include "parallel_sum.h"

#include <algorithm>
#include <vector>

#include "parallel_for.h"

namespace repose {

void parallelSums(std::size_t n, std::size_t chunk, std::size_t width, const ChunkSumBody& body, double* result) {
  chunk = std::max<std::size_t>(chunk, 1);
  const std::size_t chunks = (n + chunk - 1) / chunk;
  std::vector<double> partial(chunks * width, 0.0);
  parallelFor(chunks, [&](std::size_t first, std::size_t last) {
    for (std::size_t c = first; c < last; ++c)
      body(c * chunk, std::min(n, (c + 1) * chunk), partial.data() + c * width);
  }, 1);
  auto combine = [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      double sum = 0.0;
      for (std::size_t c = 0; c < chunks; ++c) sum += partial[c * width + k];
      result[k] = sum;
    }
  };
  if (chunks * width >= 65536)
    parallelFor(width, combine, 4096);
  else
    combine(0, width);
}

double parallelSum(std::size_t n, std::size_t chunk, const std::function<double(std::size_t, std::size_t)>& body) {
  double sum = 0.0;
  parallelSums(n, chunk, 1, [&](std::size_t begin, std::size_t end, double* partial) { *partial += body(begin, end); },
               &sum);
  return sum;
}

}  // namespace repose
