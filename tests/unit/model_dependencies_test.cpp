// The files a model reads besides itself, found once per file however many objects name it.
#include "server/client/model_dependencies.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "renderer/util/input_error.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// The files found, by the names the model uses.
std::vector<fs::path> names(const std::vector<ConfinedFile>& files) {
  std::vector<fs::path> out;
  for (const ConfinedFile& f : files) out.push_back(f.named);
  return out;
}
std::vector<fs::path> model_dependencies(const fs::path& model) { return names(farm::model_dependencies(model)); }

TEST(ModelDependencies, ObjMaterialLibrariesAndTheirMapsThatExist) {
  TempDir dir;
  std::ofstream(dir / "a.mtl") << "newmtl m\nKd 1 1 1\nmap_Kd -s 1 1 1 tex/wood.png\nmap_Ks missing.png\n";
  std::ofstream(dir / "b.mtl") << "newmtl n\n";
  fs::create_directories(dir / "tex");
  std::ofstream(dir / "tex/wood.png") << "png";
  std::ofstream(dir / "m.obj") << "mtllib a.mtl b.mtl\nv 0 0 0\n";
  const auto deps = model_dependencies(dir / "m.obj");
  const std::vector<fs::path> expected{(dir / "a.mtl").lexically_normal(), (dir / "b.mtl").lexically_normal(),
                                       (dir / "tex/wood.png").lexically_normal()};
  EXPECT_EQ(deps, expected);
}

TEST(ModelDependencies, GltfExternalBuffersAndImagesButNotDataUris) {
  TempDir dir;
  std::ofstream(dir / "mesh data.bin") << "bin";
  std::ofstream(dir / "albedo.png") << "png";
  std::ofstream(dir / "m.gltf") << R"({"asset": {"version": "2.0"},
      "buffers": [{"uri": "mesh%20data.bin", "byteLength": 3}, {"uri": "data:application/octet-stream;base64,AAAA"}],
      "images": [{"uri": "albedo.png"}, {"uri": "https://example.com/x.png"}]})";
  const auto deps = model_dependencies(dir / "m.gltf");
  const std::vector<fs::path> expected{(dir / "albedo.png").lexically_normal(), (dir / "mesh data.bin").lexically_normal()};
  EXPECT_EQ(deps, expected);
  // The test GLB embeds everything.
  EXPECT_TRUE(model_dependencies(fs::path(FARM_TEST_DATA) / "quad_scene.glb").empty());
}

TEST(ModelDependencies, ColladaImages) {
  TempDir dir;
  std::ofstream(dir / "skin.png") << "png";
  std::ofstream(dir / "m.dae") << "<COLLADA><library_images><image id=\"i\"><init_from>skin.png</init_from></image>"
                                  "</library_images><surface><init_from>i</init_from></surface></COLLADA>";
  EXPECT_EQ(model_dependencies(dir / "m.dae"), std::vector<fs::path>{(dir / "skin.png").lexically_normal()});
  EXPECT_TRUE(model_dependencies(fs::path(FARM_SHARED_ASSETS) / "dae/cow.dae").empty());
}

TEST(ModelDependencies, Collada14And15ImagesFoundAsXmlAndDecodedAsUris) {
  TempDir dir;
  for (const char* name : {"my skin.png", "a&b.png", "bump.png", "tex/mip0.png", "abs.png", "ghost.png", "i"}) {
    fs::create_directories((dir / name).parent_path());
    std::ofstream(dir / name) << "png";
  }
  // A file URI with an absolute path is refused (ModelDependencies.AbsoluteReferencesAreRefused);
  // a relative reference through a folder and back is the file it leads to.
  const std::string absolute = "tex/../abs.png";
  std::ofstream(dir / "m.dae")
      << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
         "<COLLADA xmlns=\"http://www.collada.org/2008/03/COLLADASchema\" version=\"1.5.0\">\n"
         "  <!-- <image><init_from>ghost.png</init_from></image>: a comment names nothing -->\n"
         "  <library_images>\n"
         "    <image id=\"skin\"><init_from>\n   my%20skin.png\n  </init_from></image>\n"   // 1.4, padded
         "    <image id=\"amp\"><init_from><![CDATA[a&b.png]]></init_from></image>\n"        // CDATA
         "    <image id=\"bump\"><init_from><ref>bump.png</ref></init_from></image>\n"       // 1.5
         "    <image id=\"mips\"><create_2d><init_from mip_index=\"0\"><ref>tex/mip0.png</ref></init_from>"
         "</create_2d></image>\n"
         "    <image id=\"abs\"><init_from><ref>" + absolute + "</ref></init_from></image>\n"
         "    <image id=\"inline\"><init_from><hex format=\"R8G8B8\">00ff00</hex></init_from></image>\n"
         "    <image id=\"web\"><init_from>https://example.com/x.png</init_from></image>\n"
         "    <image id=\"gone\"><init_from>missing.png</init_from></image>\n"
         "  </library_images>\n"
         // A 1.4 <surface> names the image by id: a file that happens to share the id is no reference.
         "  <library_effects><effect id=\"e\"><profile_COMMON><newparam sid=\"s\"><surface type=\"2D\">"
         "<init_from>i</init_from></surface></newparam></profile_COMMON></effect></library_effects>\n"
         "</COLLADA>\n";
  const std::vector<fs::path> expected{(dir / "a&b.png").lexically_normal(), (dir / "abs.png").lexically_normal(),
                                       (dir / "bump.png").lexically_normal(), (dir / "my skin.png").lexically_normal(),
                                       (dir / "tex/mip0.png").lexically_normal()};
  EXPECT_EQ(model_dependencies(dir / "m.dae"), expected);
}

TEST(ModelDependencies, ColladaEntitiesAndNamespacePrefixesReadAsXml) {
  TempDir dir;
  std::ofstream(dir / "a&b.png") << "png";
  std::ofstream(dir / "m.dae") << "<c:COLLADA xmlns:c=\"http://www.collada.org/2005/11/COLLADASchema\">"
                                  "<c:library_images><c:image id=\"i\"><c:init_from>a&amp;b.png</c:init_from>"
                                  "</c:image></c:library_images></c:COLLADA>";
  EXPECT_EQ(model_dependencies(dir / "m.dae"), std::vector<fs::path>{(dir / "a&b.png").lexically_normal()});
}

TEST(ModelDependencies, AMalformedColladaFileHasNoneAndIsLeftToItsLoader) {
  TempDir dir;
  std::ofstream(dir / "skin.png") << "png";
  for (const char* text : {"<COLLADA><library_images><image><init_from>skin.png</init_from></image>",  // unclosed
                           "<COLLADA><image><init_from>skin.png</image></init_from></COLLADA>",        // crossed
                           "", "not xml at all"}) {
    std::ofstream(dir / "m.dae") << text;
    EXPECT_TRUE(model_dependencies(dir / "m.dae").empty()) << text;
  }
}

TEST(ModelDependencyScanner, ReadsEachModelAndMaterialLibraryOnce) {
  TempDir dir;
  std::ofstream(dir / "wood.png") << "png";
  std::ofstream(dir / "shared.mtl") << "newmtl m\nmap_Kd wood.png\n";
  std::ofstream(dir / "a.obj") << "mtllib shared.mtl\n";
  std::ofstream(dir / "b.obj") << "mtllib shared.mtl shared.mtl\n";  // named twice, read once
  ModelDependencyScanner scanner(dir.path());
  const std::vector<fs::path> expected{(dir / "shared.mtl").lexically_normal(), (dir / "wood.png").lexically_normal()};
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(names(scanner.dependencies(dir / "a.obj")), expected);
    EXPECT_EQ(names(scanner.dependencies(dir / "./b.obj")), expected);  // the same file, however written
  }
  EXPECT_EQ(scanner.files_scanned(), 3u);
}

TEST(ModelDependencyScanner, AModelThatCannotBeReadIsNotRememberedAsHavingNone) {
  TempDir dir;
  ModelDependencyScanner scanner(dir.path());
  EXPECT_THROW(scanner.dependencies(dir / "m.obj"), InputError);
  std::ofstream(dir / "m.obj") << "v 0 0 0\n";
  EXPECT_TRUE(scanner.dependencies(dir / "m.obj").empty());
  EXPECT_EQ(scanner.files_scanned(), 1u);
}

}  // namespace
}  // namespace farm
