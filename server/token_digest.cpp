#include "server/token_digest.h"

#include <array>

#include <openssl/evp.h>

#include "core/error.h"

namespace pic {

std::string tokenDigest(std::string_view token) {
    std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
    unsigned int size = 0;
    // SHA-256 of a short string fails only with a broken OpenSSL; carrying on then could
    // let tokens match that should not.
    PIC_CHECK(EVP_Digest(token.data(), token.size(), digest.data(), &size, EVP_sha256(), nullptr) ==
                  1 &&
              size == 32);
    static constexpr char kHex[] = "0123456789abcdef";
    std::string hex(2 * size, '0');
    for (unsigned int i = 0; i < size; ++i) {
        hex[2 * i] = kHex[digest[i] >> 4];
        hex[2 * i + 1] = kHex[digest[i] & 15];
    }
    return hex;
}

}  // namespace pic
