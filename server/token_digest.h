#pragma once
/// Session tokens at rest: the server keeps only their SHA-256 digests, in memory and in its
/// database, so that neither holds a token someone who reads it could present. A token is
/// 128 random bits (service.cpp), so an unsalted digest cannot be searched back.

#include <string>
#include <string_view>

namespace pic {

/// SHA-256 of `token`, as 64 lowercase hex digits.
std::string tokenDigest(std::string_view token);

/// Compares digests in time independent of where they differ.
bool sameDigest(std::string_view a, std::string_view b);

}  // namespace pic
