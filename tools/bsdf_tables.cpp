// Writes the BSDFs' quadrature tables as C++ aggregate initialisers of exact hex floats, run by
// the build so that no process integrates them at run time: OUTDIR/ggx_albedo_table.inc (the GGX
// albedos, renderer/trace/ggx_albedo_quadrature.h) and OUTDIR/coat_tables.inc (the dielectric
// coat's 41 tables, renderer/trace/dielectric_coat_quadrature.h), included by ggx_albedo.cpp and
// dielectric_coat.cpp. The coat's tables, 0.16 s each, are integrated on every hardware thread.
// Usage: farm_bsdf_tables OUTDIR
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "renderer/trace/dielectric_coat_quadrature.h"
#include "renderer/trace/ggx_albedo_quadrature.h"

namespace {

void write_floats(std::FILE* out, const auto& values) {
  std::fprintf(out, "{{");
  for (const float e : values) std::fprintf(out, "%a,", static_cast<double>(e));
  std::fprintf(out, "}}");
}

// A table of rows and one row more: {{rows...}, {extra}}, as both tables' structs are laid out.
void write_table(std::FILE* out, const auto& rows, const auto& extra) {
  std::fprintf(out, "{\n {{\n");
  for (const auto& row : rows) {
    std::fprintf(out, "  ");
    write_floats(out, row);
    std::fprintf(out, ",\n");
  }
  std::fprintf(out, " }},\n ");
  write_floats(out, extra);
  std::fprintf(out, "\n}");
}

bool write_file(const std::string& path, const auto& write) {
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (!out) {
    std::perror(path.c_str());
    return false;
  }
  std::fprintf(out, "// Written by tools/bsdf_tables.cpp at build time: do not edit.\n");
  write(out);
  if (std::fclose(out) != 0) {
    std::perror(path.c_str());
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUTDIR\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  const farm::ggx::AlbedoTable albedo = farm::ggx::albedo_table_by_quadrature();
  std::vector<farm::coat::CoatTable> coats(farm::coat::kEtaSteps);
  std::atomic<int> next{0};
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < std::max(1u, std::thread::hardware_concurrency()); ++t) {
    threads.emplace_back([&] {
      for (int i = next++; i < farm::coat::kEtaSteps; i = next++) {
        coats[static_cast<std::size_t>(i)] = farm::coat::coat_table_by_quadrature(i);
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  const bool ok = write_file(dir + "/ggx_albedo_table.inc",
                             [&](std::FILE* out) { write_table(out, albedo.directional, albedo.average); });
  const bool coats_ok = write_file(dir + "/coat_tables.inc", [&](std::FILE* out) {
    std::fprintf(out, "{{\n");
    for (const farm::coat::CoatTable& table : coats) {
      write_table(out, table.transmittance, table.internal_reflectance);
      std::fprintf(out, ",\n");
    }
    std::fprintf(out, "}}\n");
  });
  return ok && coats_ok ? 0 : 1;
}
