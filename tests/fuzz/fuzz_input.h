#pragma once
// What every fuzz target shares: the input as text, and the rule that a reader may reject any text
// with an exception (its one-line error) but must not crash, hang or break its own invariants.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

inline std::string fuzzText(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

/// An invariant of an accepted input that does not hold: reported as a crash, with its reason.
[[noreturn]] inline void fuzzInvariantBroken(const char* what) {
  std::fprintf(stderr, "invariant broken: %s\n", what);
  std::abort();
}
