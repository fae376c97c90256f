// The one containment rule (renderer/util/path_confinement.h) that confine_file, suites and
// rubrics build on: `..` and symlinks cannot lead out, and a sibling sharing a prefix is out.
#include "renderer/util/path_confinement.h"

#include <gtest/gtest.h>

#include <fstream>

#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

TEST(PathConfinement, InsideOutsideDotDotSymlinksAndPrefixSiblings) {
  test::TempDir dir;
  const fs::path root = fs::weakly_canonical(dir / "assets");
  fs::create_directories(root / "models");
  fs::create_directories(dir / "assets2");
  std::ofstream(root / "models" / "cow.dae") << "x";
  std::ofstream(dir / "assets2" / "secret.dae") << "x";
  std::ofstream(dir / "outside.dae") << "x";
  fs::create_symlink(dir / "outside.dae", root / "models" / "link.dae");
  fs::create_symlink(root / "models" / "cow.dae", root / "inner_link.dae");

  EXPECT_TRUE(resolve_within(root, root / "models" / "cow.dae"));
  EXPECT_TRUE(resolve_within(root, root / "models" / ".." / "models" / "cow.dae"));
  EXPECT_TRUE(resolve_within(root, root / "not_yet_there.dae"));  // containment before existence
  EXPECT_EQ(*resolve_within(root, root / "inner_link.dae"), root / "models" / "cow.dae");
  EXPECT_FALSE(resolve_within(root, root / ".." / "outside.dae"));
  EXPECT_FALSE(resolve_within(root, root / "models" / "link.dae"));  // a symlink out
  EXPECT_FALSE(resolve_within(root, dir / "assets2" / "secret.dae"));  // /assets2 is not /assets
  EXPECT_FALSE(resolve_within(root, "/etc/passwd"));
  EXPECT_TRUE(lies_within(root / "", root / "models"));  // a trailing separator on the root
  EXPECT_TRUE(lies_within(root, root));
}

}  // namespace
}  // namespace farm
