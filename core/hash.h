#pragma once
/// A fast non-cryptographic 64-bit hash for checksums and scene identity.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace pic {

/// 64-bit hash of a byte range, continuing from `seed` (chain calls to hash several ranges).
uint64_t hashBytes(const void* data, size_t size, uint64_t seed = 0x9E3779B97F4A7C15ull);

/// Hash of a vector's contents.
template <class T>
uint64_t hashVector(const std::vector<T>& v, uint64_t seed = 0x9E3779B97F4A7C15ull) {
    return hashBytes(v.data(), v.size() * sizeof(T), seed);
}

}  // namespace pic
