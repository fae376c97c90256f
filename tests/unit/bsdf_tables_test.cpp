// The BSDF tables the build computed (tools/bsdf_tables.cpp) against their quadrature computed
// here, now: the same bits in every entry, so that writing and reading them back lost nothing and
// the generator ran the renderer's own code.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>

#include "renderer/trace/dielectric_coat.h"
#include "renderer/trace/dielectric_coat_quadrature.h"
#include "renderer/trace/ggx.h"
#include "renderer/trace/ggx_albedo_quadrature.h"

namespace farm {
namespace {

TEST(GgxAlbedo, TheBuiltTableIsTheQuadratureComputedHereBitForBit) {
  const ggx::AlbedoTable now = ggx::albedo_table_by_quadrature();
  const ggx::AlbedoTable& built = ggx::built_albedo_table();
  for (int i = 0; i < ggx::kAlbedoAlphaSteps; ++i) {
    const auto a = static_cast<std::size_t>(i);
    for (int j = 0; j < ggx::kAlbedoMuSteps; ++j) {
      const auto m = static_cast<std::size_t>(j);
      EXPECT_EQ(std::bit_cast<std::uint32_t>(built.directional[a][m]), std::bit_cast<std::uint32_t>(now.directional[a][m]))
          << "alpha step " << i << ", mu step " << j << ": " << built.directional[a][m] << " vs " << now.directional[a][m];
    }
    EXPECT_EQ(std::bit_cast<std::uint32_t>(built.average[a]), std::bit_cast<std::uint32_t>(now.average[a])) << i;
  }
  // And what the BSDF reads is that table: at a grid point, the entry itself.
  EXPECT_EQ(ggx::directional_albedo(1.0f, 1.0f), built.directional[ggx::kAlbedoAlphaSteps - 1][ggx::kAlbedoMuSteps - 1]);
  EXPECT_EQ(ggx::average_albedo(0.0f), built.average[0]);
  // A smooth lobe seen head-on loses next to nothing; the roughest, seen at a grazing angle
  // (mu = 3/31), a fifth or more.
  EXPECT_GT(built.directional[1][ggx::kAlbedoMuSteps - 1], 0.99f);
  EXPECT_LT(built.directional[ggx::kAlbedoAlphaSteps - 1][3], 0.8f);
}

// Three of the coat's 41 tables (each 0.16 s to integrate): the grid's ends and glTF's default
// ior 1.5; and a coat of ior 1.5 reads the table of its grid point alone.
TEST(CoatTables, TheBuiltTablesAreTheQuadratureComputedHereBitForBit) {
  const auto& built = coat::built_coat_tables();
  for (const int e : {0, 10, coat::kEtaSteps - 1}) {
    const coat::CoatTable now = coat::coat_table_by_quadrature(e);
    const coat::CoatTable& table = built[static_cast<std::size_t>(e)];
    for (int i = 0; i < coat::kAlphaSteps; ++i) {
      const auto a = static_cast<std::size_t>(i);
      for (int j = 0; j < coat::kMuSteps; ++j) {
        const auto m = static_cast<std::size_t>(j);
        EXPECT_EQ(std::bit_cast<std::uint32_t>(table.transmittance[a][m]), std::bit_cast<std::uint32_t>(now.transmittance[a][m]))
            << "eta step " << e << ", alpha step " << i << ", mu step " << j;
      }
      EXPECT_EQ(std::bit_cast<std::uint32_t>(table.internal_reflectance[a]),
                std::bit_cast<std::uint32_t>(now.internal_reflectance[a]))
          << "eta step " << e << ", alpha step " << i;
    }
  }
  const DielectricCoat coat(1.5f, 1.0f);  // alpha 1: the last grid row
  EXPECT_EQ(coat.transmittance(1.0f), built[10].transmittance[coat::kAlphaSteps - 1][coat::kMuSteps - 1]);
  EXPECT_EQ(coat.internal_reflectance(), built[10].internal_reflectance[coat::kAlphaSteps - 1]);
  // An index of 1 is no interface: everything passes it head-on.
  EXPECT_GT(built[0].transmittance[1][coat::kMuSteps - 1], 0.99f);
}

}  // namespace
}  // namespace farm
