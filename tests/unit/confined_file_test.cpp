// The one gate for files named by input (renderer/util/confined_file.h): every verdict, the
// message naming the referrer and the reference, and an open that never follows a swapped-in link
// and never waits on a FIFO.
#include "renderer/util/confined_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// root/                     the asset root
//   models/m.obj            the referrer
//   models/lib.mtl
//   models/inner.mtl     -> lib.mtl (a link that stays inside)
//   models/escape.mtl    -> ../../outside/secret.mtl
//   models/outdir        -> ../../outside (a folder link that leads out)
//   models/fifo.mtl         a FIFO
//   models/folder.mtl/      a directory
// outside/secret.mtl
class ConfinedFileTest : public ::testing::Test {
 protected:
  ConfinedFileTest() {
    fs::create_directories(dir_ / "root/models/folder.mtl");
    fs::create_directories(dir_ / "outside");
    root_ = fs::weakly_canonical(dir_ / "root");
    model_ = root_ / "models/m.obj";
    std::ofstream(model_) << "mtllib lib.mtl\n";
    std::ofstream(root_ / "models/lib.mtl") << "newmtl m\n";
    std::ofstream(dir_ / "outside/secret.mtl") << "newmtl secret\n";
    fs::create_symlink("lib.mtl", root_ / "models/inner.mtl");
    fs::create_symlink("../../outside/secret.mtl", root_ / "models/escape.mtl");
    fs::create_symlink("../../outside", root_ / "models/outdir");
    EXPECT_EQ(::mkfifo((root_ / "models/fifo.mtl").c_str(), 0600), 0);
  }

  ConfinedFile confine(const std::string& reference, ReferenceForm form = ReferenceForm::relative) {
    return confine_file(root_, model_, reference, form);
  }

  test::TempDir dir_;
  fs::path root_, model_;
};

TEST_F(ConfinedFileTest, ARegularFileInsideIsAllowedWithItsSize) {
  const ConfinedFile f = confine("lib.mtl");
  ASSERT_TRUE(f.allowed()) << f.message;
  EXPECT_EQ(f.named, root_ / "models/lib.mtl");
  EXPECT_EQ(f.resolved, root_ / "models/lib.mtl");
  EXPECT_EQ(f.size, 9u);
  EXPECT_TRUE(f.message.empty());
  EXPECT_TRUE(confine("../models/./lib.mtl").allowed());  // `..` that stays inside
}

TEST_F(ConfinedFileTest, ASymlinkInsideThatPointsInsideIsAllowedUnderItsOwnName) {
  const ConfinedFile f = confine("inner.mtl");
  ASSERT_TRUE(f.allowed()) << f.message;
  EXPECT_EQ(f.named, root_ / "models/inner.mtl");  // where a farm lays it out
  EXPECT_EQ(f.resolved, root_ / "models/lib.mtl");  // what is read
}

TEST_F(ConfinedFileTest, DotDotOutOfTheRootIsRefusedNamingReferrerAndReference) {
  for (const std::string ref : {"../../outside/secret.mtl", "../../../../../../../etc/passwd",
                                "../../outside/missing.mtl", "../../root2/x.mtl"}) {
    SCOPED_TRACE(ref);
    const ConfinedFile f = confine(ref);
    EXPECT_EQ(f.verdict, Confinement::outside);
    EXPECT_TRUE(f.refused());
    EXPECT_EQ(f.message, model_.string() + ": '" + ref + "' lies outside the asset root (" + root_.string() + ")");
  }
}

TEST_F(ConfinedFileTest, AbsoluteReferencesAreRefusedFromModelsAndConfinedFromJobs) {
  const std::string inside = (root_ / "models/lib.mtl").string();
  const ConfinedFile from_model = confine(inside);
  EXPECT_EQ(from_model.verdict, Confinement::absolute);
  EXPECT_TRUE(contains(from_model.message, "'" + inside + "' is an absolute path")) << from_model.message;
  EXPECT_EQ(confine("/etc/passwd").verdict, Confinement::absolute);

  EXPECT_TRUE(confine(inside, ReferenceForm::relative_or_absolute).allowed());
  const ConfinedFile elsewhere = confine((dir_ / "outside/secret.mtl").string(), ReferenceForm::relative_or_absolute);
  EXPECT_EQ(elsewhere.verdict, Confinement::outside);
  EXPECT_TRUE(contains(elsewhere.reason, "lies outside the asset root")) << elsewhere.reason;
}

TEST_F(ConfinedFileTest, SymlinksThatLeadOutAreRefused) {
  for (const std::string ref : {"escape.mtl", "outdir/secret.mtl"}) {
    SCOPED_TRACE(ref);
    const ConfinedFile f = confine(ref);
    EXPECT_EQ(f.verdict, Confinement::outside);
    EXPECT_TRUE(contains(f.message, "'" + ref + "' lies outside the asset root")) << f.message;
    EXPECT_TRUE(contains(f.message, "symbolic link")) << f.message;
    EXPECT_FALSE(contains(f.message, "secret.mtl") && ref == "escape.mtl") << "the target is not shown";
  }
}

TEST_F(ConfinedFileTest, FifosDirectoriesAndDevicesAreNotRegularFiles) {
  const ConfinedFile fifo = confine("fifo.mtl");
  EXPECT_EQ(fifo.verdict, Confinement::not_regular);
  EXPECT_EQ(fifo.message, model_.string() + ": 'fifo.mtl' is a FIFO, not a regular file");
  const ConfinedFile folder = confine("folder.mtl");
  EXPECT_EQ(folder.verdict, Confinement::not_regular);
  EXPECT_TRUE(contains(folder.message, "'folder.mtl' is a directory")) << folder.message;
  EXPECT_EQ(confine(".").verdict, Confinement::not_regular);
  // A device, where the root holds one (a root of "/" is what it takes to reach /dev/null).
  const ConfinedFile device = confine_file("/", "/dev/x", "null");
  EXPECT_EQ(device.verdict, Confinement::not_regular);
  EXPECT_TRUE(contains(device.message, "'null' is a character device")) << device.message;
}

TEST_F(ConfinedFileTest, MissingFilesInsideAreMissingAndOddNamesAreRefused) {
  EXPECT_EQ(confine("nope.mtl").verdict, Confinement::missing);
  EXPECT_EQ(confine("lib.mtl/below").verdict, Confinement::missing);
  EXPECT_EQ(confine("").verdict, Confinement::missing);
  EXPECT_FALSE(confine("nope.mtl").refused());
  EXPECT_EQ(confine(std::string("lib.mtl\0x", 9)).verdict, Confinement::inaccessible);
}

TEST_F(ConfinedFileTest, OpenReadsTheCheckedFileAndRefusesOneSwappedAfterTheCheck) {
  const ConfinedFile lib = confine("lib.mtl");
  std::string bytes, why;
  ASSERT_TRUE(read_confined(lib, bytes, &why)) << why;
  EXPECT_EQ(bytes, "newmtl m\n");

  // Swapped for a FIFO after the check: the open neither blocks nor reads.
  fs::remove(root_ / "models/lib.mtl");
  ASSERT_EQ(::mkfifo((root_ / "models/lib.mtl").c_str(), 0600), 0);
  EXPECT_EQ(open_confined(lib, &why), -1);
  EXPECT_TRUE(contains(why, "replaced")) << why;

  // Swapped for a link to the secret: not followed.
  fs::remove(root_ / "models/lib.mtl");
  fs::create_symlink(dir_ / "outside/secret.mtl", root_ / "models/lib.mtl");
  EXPECT_FALSE(read_confined(lib, bytes, &why));
  EXPECT_FALSE(contains(bytes, "secret"));

  // Refused files are never opened.
  EXPECT_EQ(open_confined(confine("fifo.mtl"), &why), -1);
  EXPECT_TRUE(contains(why, "FIFO")) << why;
}

}  // namespace
}  // namespace farm
