// Plain peers of the posing stages for scripts/benchmark.py's ratio columns: what each stage would
// cost with nothing but its memory traffic left.
//
// usage: repose_stage_peers gather LABELS.raw BYTES_PER_LABEL REST_DIMS(3) REST_TO_INDEX(12)
//                                  FIELD.raw POSED_DIMS(3) POSED_TO_PHYSICAL(12) REPEATS
//   Nearest-neighbour labels at x + d(x) for every posed voxel x (d: the ready displacement field,
//   float xyz per voxel, x fastest), written once; 0 outside the rest grid. Affines are row-major 3x4:
//   REST_TO_INDEX maps a physical point to continuous rest indices, POSED_TO_PHYSICAL posed indices to
//   physical points. One thread. Prints "gather cpu_ms MS checksum C" (MS: the fastest of REPEATS
//   runs, in process CPU time; C: the sum of the labels written, so the work cannot be skipped).
//   BYTES_PER_LABEL 0: the rest volume is float intensities, sampled trilinearly (the posed CT's peer;
//   samples outside the rest grid's centres are 0), the checksum their rounded sum.
//        repose_stage_peers triad BYTES REPEATS
//   STREAM's triad a = b + s c on doubles, the three arrays BYTES together, split over every hardware
//   thread (the memory bandwidth a stage moving BYTES cannot beat). Prints "triad ms MS" (fastest run).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>
#include <ctime>
#include <thread>
#include <vector>

namespace {

double cpuMilliseconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

std::vector<char> readAll(const char* path) {
  std::FILE* f = std::fopen(path, "rb");
  if (!f) {
    std::fprintf(stderr, "repose_stage_peers: cannot read %s\n", path);
    std::exit(1);
  }
  std::fseek(f, 0, SEEK_END);
  std::vector<char> data(std::size_t(std::ftell(f)));
  std::fseek(f, 0, SEEK_SET);
  if (std::fread(data.data(), 1, data.size(), f) != data.size()) std::exit(1);
  std::fclose(f);
  return data;
}

// Calls out[n] = sample(q) for every posed voxel n, q its continuous rest index through the field, and
// returns the CPU ms it took; then the checksum of what was written.
template <class Value, class Sample>
double gatherWith(const double* toIndex, const float* field, const long* pd, const double* toPhysical,
                  std::vector<Value>& out, long long& checksum, Sample&& sample) {
  const double t0 = cpuMilliseconds();
  std::size_t n = 0;
  for (long k = 0; k < pd[2]; ++k)
    for (long j = 0; j < pd[1]; ++j)
      for (long i = 0; i < pd[0]; ++i, ++n) {
        double p[3], q[3];
        for (int r = 0; r < 3; ++r)
          p[r] = toPhysical[4 * r] * i + toPhysical[4 * r + 1] * j + toPhysical[4 * r + 2] * k + toPhysical[4 * r + 3] +
                 field[3 * n + r];
        for (int r = 0; r < 3; ++r)
          q[r] = toIndex[4 * r] * p[0] + toIndex[4 * r + 1] * p[1] + toIndex[4 * r + 2] * p[2] + toIndex[4 * r + 3];
        out[n] = sample(q);
      }
  const double ms = cpuMilliseconds() - t0;
  double sum = 0;
  for (const Value v : out) sum += double(v);
  checksum = std::llround(sum);
  return ms;
}

template <class Label>
double gather(const Label* rest, const long* rd, const double* toIndex, const float* field, const long* pd,
              const double* toPhysical, std::vector<Label>& out, long long& checksum) {
  return gatherWith(toIndex, field, pd, toPhysical, out, checksum, [&](const double* q) {
    const double f[3] = {std::floor(q[0] + 0.5), std::floor(q[1] + 0.5), std::floor(q[2] + 0.5)};
    const bool inside = f[0] >= 0 && f[1] >= 0 && f[2] >= 0 && f[0] < rd[0] && f[1] < rd[1] && f[2] < rd[2];
    return inside ? rest[(long(f[2]) * rd[1] + long(f[1])) * rd[0] + long(f[0])] : Label(0);
  });
}

// Trilinear intensity at rest index q (continuous); 0 unless the 8 neighbours are inside the grid.
inline float trilinear(const float* rest, const long* rd, const double* q) {
  const double f[3] = {std::floor(q[0]), std::floor(q[1]), std::floor(q[2])};
  if (f[0] < 0 || f[1] < 0 || f[2] < 0 || f[0] + 1 >= rd[0] || f[1] + 1 >= rd[1] || f[2] + 1 >= rd[2]) return 0.0f;
  const double t[3] = {q[0] - f[0], q[1] - f[1], q[2] - f[2]};
  const float* c = rest + (long(f[2]) * rd[1] + long(f[1])) * rd[0] + long(f[0]);
  const long sy = rd[0], sz = rd[0] * rd[1];
  const double x00 = c[0] + t[0] * (c[1] - c[0]), x10 = c[sy] + t[0] * (c[sy + 1] - c[sy]);
  const double x01 = c[sz] + t[0] * (c[sz + 1] - c[sz]), x11 = c[sz + sy] + t[0] * (c[sz + sy + 1] - c[sz + sy]);
  const double y0 = x00 + t[1] * (x10 - x00), y1 = x01 + t[1] * (x11 - x01);
  return float(y0 + t[2] * (y1 - y0));
}

int gatherMain(char** a) {
  const std::vector<char> labels = readAll(a[0]);
  const int bytes = std::atoi(a[1]);
  long rd[3], pd[3];
  double toIndex[12], toPhysical[12];
  for (int i = 0; i < 3; ++i) rd[i] = std::atol(a[2 + i]);
  for (int i = 0; i < 12; ++i) toIndex[i] = std::atof(a[5 + i]);
  const std::vector<char> fieldData = readAll(a[17]);
  for (int i = 0; i < 3; ++i) pd[i] = std::atol(a[18 + i]);
  for (int i = 0; i < 12; ++i) toPhysical[i] = std::atof(a[21 + i]);
  const int repeats = std::max(1, std::atoi(a[33]));
  const std::size_t voxels = std::size_t(pd[0] * pd[1] * pd[2]);
  const std::size_t restBytes = std::size_t(rd[0] * rd[1] * rd[2]) * (bytes == 0 ? sizeof(float) : std::size_t(bytes));
  if (fieldData.size() != voxels * 3 * sizeof(float) || labels.size() != restBytes) {
    std::fprintf(stderr, "repose_stage_peers: the files do not match the dimensions\n");
    return 1;
  }
  const auto* field = reinterpret_cast<const float*>(fieldData.data());
  double best = 1e300;
  long long checksum = 0;
  for (int r = 0; r < repeats; ++r) {
    if (bytes == 0) {
      std::vector<float> out(voxels);
      const auto* rest = reinterpret_cast<const float*>(labels.data());
      best = std::min(best, gatherWith(toIndex, field, pd, toPhysical, out, checksum,
                                       [&](const double* q) { return trilinear(rest, rd, q); }));
    } else if (bytes == 1) {
      std::vector<std::uint8_t> out(voxels);
      best = std::min(best, gather(reinterpret_cast<const std::uint8_t*>(labels.data()), rd, toIndex, field, pd,
                                   toPhysical, out, checksum));
    } else if (bytes == 2) {
      std::vector<std::uint16_t> out(voxels);
      best = std::min(best, gather(reinterpret_cast<const std::uint16_t*>(labels.data()), rd, toIndex, field, pd,
                                   toPhysical, out, checksum));
    } else {
      std::vector<std::int32_t> out(voxels);
      best = std::min(best, gather(reinterpret_cast<const std::int32_t*>(labels.data()), rd, toIndex, field, pd,
                                   toPhysical, out, checksum));
    }
  }
  std::printf("gather cpu_ms %.3f checksum %lld\n", best, checksum);
  return 0;
}

int triadMain(char** a) {
  const std::size_t n = std::max<std::size_t>(1, std::size_t(std::atof(a[0])) / (3 * sizeof(double)));
  const int repeats = std::max(1, std::atoi(a[1]));
  std::vector<double> x(n, 0.0), y(n, 1.0), z(n, 2.0);
  const unsigned workers = std::max(1u, std::thread::hardware_concurrency());
  const auto triad = [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) x[i] = y[i] + 3.0 * z[i];
  };
  double best = 1e300;
  for (int r = 0; r <= repeats; ++r) {  // the first run pages the arrays in and is not counted
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::thread> threads;
    for (unsigned w = 0; w < workers; ++w) threads.emplace_back(triad, n * w / workers, n * (w + 1) / workers);
    for (auto& t : threads) t.join();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (r > 0) best = std::min(best, ms);
  }
  std::printf("triad ms %.4f check %.1f\n", best, x[n / 2]);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 36 && std::string_view(argv[1]) == "gather") return gatherMain(argv + 2);
  if (argc == 4 && std::string_view(argv[1]) == "triad") return triadMain(argv + 2);
  std::fprintf(stderr, "usage: %s gather ... | triad BYTES REPEATS (see the source's header)\n", argv[0]);
  return 1;
}
