// Session tokens are kept as SHA-256 digests (server/token_digest.h).

#include <gtest/gtest.h>

#include "server/token_digest.h"

namespace pic {
namespace {

TEST(TokenDigest, IsSha256AsLowercaseHex) {
    // FIPS 180-2 test vectors.
    EXPECT_EQ(tokenDigest("abc"),
              "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    EXPECT_EQ(tokenDigest(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    EXPECT_NE(tokenDigest("0123456789abcdef0123456789abcdef"),
              tokenDigest("0123456789abcdef0123456789abcdee"));
}

}  // namespace
}  // namespace pic
