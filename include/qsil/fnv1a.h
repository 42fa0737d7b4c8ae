#pragma once
/// @file fnv1a.h
/// FNV-1a, the 64-bit non-cryptographic hash of a byte range: fingerprints that tell whether a
/// mesh changed (EdgeSet's refit check, the Python ReverseEstimator's stale-scene check).

#include <cstddef>
#include <cstdint>

namespace qsil {

/// FNV-1a's 64-bit offset basis: the hash of no bytes, where a chain of fnv1a calls starts.
inline constexpr std::uint64_t kFnv1aBasis = 1469598103934665603ull;

/// The FNV-1a hash of `bytes` bytes at `data`, continuing from `h` (kFnv1aBasis to start).
inline std::uint64_t fnv1a(const void* data, std::size_t bytes, std::uint64_t h = kFnv1aBasis) {
  const auto* b = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) {
    h ^= b[i];
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace qsil
