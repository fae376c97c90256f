// The pieces of issue #15's access control that need no server: the tokens file, roles, and
// which listen addresses count as loopback.
#include <gtest/gtest.h>

#include <string>

#include "renderer/util/input_error.h"
#include "server/common/listen_policy.h"
#include "server/common/sha256.h"
#include "server/common/token_table.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

// The message of the InputError `load` throws; empty when it throws none.
std::string load_error(const std::string& text) {
  test::TempDir dir;
  try {
    TokenTable::load(dir.write("tokens", text));
  } catch (const InputError& e) {
    return e.what();
  }
  return {};
}

const std::string kToken = "0123456789abcdef-token";

TEST(TokenTable, FindsATokenByItsHashWithItsNameAndRoles) {
  test::TempDir dir;
  const TokenTable table = TokenTable::load(dir.write(
      "tokens", "# comment\n\n" + sha256_hex(kToken) + "  alice  submit,read  # trailing comment\n" +
                    sha256_hex("another-token-0123456") + " bob admin weight=2.5\n"));
  EXPECT_EQ(table.size(), 2u);
  const auto alice = table.find(kToken);
  ASSERT_TRUE(alice);
  EXPECT_EQ(alice->name, "alice");
  EXPECT_TRUE(alice->roles.has(Role::submit));
  EXPECT_TRUE(alice->roles.has(Role::read));
  EXPECT_FALSE(alice->roles.has(Role::admin));
  EXPECT_EQ(to_string(alice->roles), "submit,read");
  EXPECT_EQ(alice->share_weight_milli, 1000);  // no weight: 1
  EXPECT_EQ(table.find("another-token-0123456")->share_weight_milli, 2500);
  EXPECT_FALSE(table.find(sha256_hex(kToken)));  // the hash itself is no token
  EXPECT_FALSE(table.find(kToken + "x"));
}

TEST(TokenTable, BadFilesNameTheLineAndNeverHoldTokens) {
  const std::string hash = sha256_hex(kToken);
  EXPECT_NE(load_error("\n" + kToken + " alice submit\n").find("tokens:2: the first field must be the token's SHA-256"),
            std::string::npos);
  EXPECT_NE(load_error(hash + " alice\n").find("tokens:1: expected '<sha256 of the token> <name> <roles> [weight=W]'"),
            std::string::npos);
  EXPECT_NE(load_error(hash + " alice submit 2\n").find("tokens:1: '2': the fourth field is the owner's fair-share weight"),
            std::string::npos);
  EXPECT_NE(load_error(hash + " alice submit weight=0\n").find("weight=W with W from 0.001 to 1000"), std::string::npos);
  EXPECT_NE(load_error(hash + " alice submit weight=1 extra\n").find("tokens:1: expected"), std::string::npos);
  EXPECT_NE(load_error(hash + " alice root\n").find("tokens:1: unknown role 'root'"), std::string::npos);
  EXPECT_NE(load_error(hash + " al/ice submit\n").find("tokens:1: name 'al/ice'"), std::string::npos);
  EXPECT_NE(load_error(hash + " alice submit\n" + hash + " bob submit\n").find("tokens:2: the same token is listed twice"),
            std::string::npos);
  EXPECT_NE(load_error(hash + " alice submit\n" + sha256_hex("x-0123456789abcdef") + " alice read\n")
                .find("tokens:2: name 'alice' is listed twice"),
            std::string::npos);
  EXPECT_NE(load_error("# nothing\n").find("lists no tokens"), std::string::npos);
  EXPECT_EQ(load_error(hash + " alice submit\n"), "");
}

TEST(TokenTable, ClientTokensMustBeWellFormed) {
  EXPECT_TRUE(well_formed_token(kToken));
  EXPECT_FALSE(well_formed_token("short"));
  EXPECT_FALSE(well_formed_token("has a space in the middle"));
  EXPECT_FALSE(well_formed_token(std::string(513, 'a')));
  test::TempDir dir;
  EXPECT_EQ(read_client_token(dir.write("t", kToken + "\r\n")), kToken);
  EXPECT_THROW(read_client_token(dir.write("u", "x\n")), InputError);
  EXPECT_THROW(read_client_token(dir / "missing"), InputError);
}

TEST(ListenPolicy, LoopbackAddressesAreTheOnlyOnesServedWithoutAuthentication) {
  for (const char* a : {"127.0.0.1:50051", "127.1.2.3:0", "localhost:50051", "[::1]:50051", "unix:/tmp/farm.sock"}) {
    EXPECT_TRUE(is_loopback_listen(a)) << a;
    EXPECT_TRUE(check_listen_security({a, false, false, false, false}, "test").empty()) << a;
  }
  for (const char* a : {"0.0.0.0:50051", "[::]:50051", "10.0.0.5:1", "render01:50051", "127.0.0.1.evil.com:1",
                        "128.0.0.1:1"}) {
    EXPECT_FALSE(is_loopback_listen(a)) << a;
    EXPECT_THROW(check_listen_security({a, false, false, false, false}, "test"), InputError) << a;
    EXPECT_EQ(check_listen_security({a, false, false, false, true}, "test").size(), 1u) << a;   // --insecure
    EXPECT_EQ(check_listen_security({a, true, false, true, false}, "test").size(), 0u) << a;    // tokens + TLS
    EXPECT_EQ(check_listen_security({a, false, true, true, false}, "test").size(), 0u) << a;    // mTLS
    EXPECT_EQ(check_listen_security({a, true, false, false, false}, "test").size(), 1u) << a;   // plain-text tokens
  }
}

}  // namespace
}  // namespace farm
