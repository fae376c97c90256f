#include "server/common/random_token.h"

#include <openssl/rand.h>

#include <array>
#include <stdexcept>

#include "server/common/hex.h"

namespace farm {

std::string random_token() {
  std::array<unsigned char, 32> bytes{};
  if (RAND_bytes(bytes.data(), static_cast<int>(bytes.size())) != 1) {
    throw std::runtime_error("no random bytes from OpenSSL");
  }
  return to_hex(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace farm
