#pragma once
// Secrets made here: bearer tokens (`farm token`) and the dashboard's session ids.
#include <string>

namespace farm {

// 256 random bits from OpenSSL's CSPRNG, as 64 lowercase hex digits. std::runtime_error when
// OpenSSL has none to give.
std::string random_token();

}  // namespace farm
