// HOST:PORT addresses (server/common/network_address.h): which name this server, which a worker
// may register with, and which lie on this host (spot-checked only beyond it by default).
#include <gtest/gtest.h>

#include "server/common/network_address.h"

namespace farm {
namespace {

TEST(NetworkAddress, AServerKnowsItsOwnAddressUnderEveryLoopbackName) {
  EXPECT_TRUE(names_own_server("127.0.0.1:5000", "127.0.0.1", 5000));
  EXPECT_TRUE(names_own_server("localhost:5000", "127.0.0.1", 5000));
  EXPECT_TRUE(names_own_server("dns:///localhost:5000", "0.0.0.0", 5000));
  EXPECT_TRUE(names_own_server("[::1]:5000", "[::]", 5000));
  EXPECT_TRUE(names_own_server("farm-1:5000", "farm-1", 5000));
  EXPECT_FALSE(names_own_server("127.0.0.1:5001", "127.0.0.1", 5000));
  EXPECT_FALSE(names_own_server("farm-2:5000", "127.0.0.1", 5000));
}

TEST(NetworkAddress, AWorkerAddressIsAHostAndAPort) {
  for (const char* good : {"127.0.0.1:9", "worker-7.farm.example:50052", "[::1]:80", "[fe80::1]:1"}) {
    EXPECT_EQ(worker_address_problem(good), "") << good;
  }
  for (const char* bad : {"", "unix:/tmp/s", "host", "host:0", "host:65536", "a b:1", "http://h:1", ":1", "[x]:1"}) {
    EXPECT_NE(worker_address_problem(bad), "") << bad;
  }
}

TEST(NetworkAddress, OnlyLoopbackAndTheInProcessWorkerAreOnThisHost) {
  for (const char* here : {"in-process", "127.0.0.1:5000", "127.3.4.5:9", "localhost:1", "[::1]:1"}) {
    EXPECT_TRUE(on_this_host(here)) << here;
  }
  for (const char* there : {"10.0.0.2:5000", "farm-2:5000", "192.168.1.4:1", "[fe80::1]:1"}) {
    EXPECT_FALSE(on_this_host(there)) << there;
  }
}

}  // namespace
}  // namespace farm
