#pragma once
// Assimp's file access for our loaders: Assimp opens a model, and the files it names (an OBJ's
// material libraries), through an IOSystem. This one opens only what confine_file allows, without
// blocking, and remembers the first file it refused so that the load fails naming it: a refused
// material library would otherwise pass as a missing one, silently, with default materials.
#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <string>

#include "renderer/loaders/loaders.h"

namespace farm {

class ConfinedIOSystem final : public Assimp::IOSystem {
 public:
  explicit ConfinedIOSystem(const ModelFile& model) : model_(model) {}

  // True unless nothing is there: a refused file "exists", so that the importer asks to open it
  // and the refusal is remembered.
  bool Exists(const char* file) const override;
  char getOsSeparator() const override { return '/'; }
  // Read-only; nullptr for a missing or refused file, or any mode that would write.
  Assimp::IOStream* Open(const char* file, const char* mode = "rb") override;
  void Close(Assimp::IOStream* stream) override;

  // "'<reference>' <reason>" for the first file refused; empty when none was.
  const std::string& refusal() const { return refusal_; }

 private:
  ConfinedFile confine(const char* file) const;

  const ModelFile& model_;
  mutable std::string refusal_;  // Exists is const in Assimp's interface
};

}  // namespace farm
