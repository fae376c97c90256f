#include "server/client/model_dependencies.h"

#include <fmt/format.h>

#include "renderer/util/input_error.h"

namespace farm {

namespace fs = std::filesystem;

// References resolved on this machine's disk, under the asset root.
class ModelDependencyScanner::OnDisk final : public ReferenceSource {
 public:
  explicit OnDisk(fs::path root) : root_(std::move(root)) {}

  std::optional<fs::path> locate(const fs::path& model, const fs::path& referrer,
                                 const ModelReference& reference) override {
    ConfinedFile file = confine_file(root_, referrer, reference.local);
    if (file.verdict == Confinement::missing) return std::nullopt;
    if (!file.allowed()) {
      // Named by the model, or by a material library the model names.
      std::string message = referrer == model ? file.message : model.string() + ": " + file.message;
      if (file.verdict == Confinement::outside) message += " (give --asset-root a folder that holds both)";
      throw InputError(message);
    }
    fs::path named = file.named;
    located_.insert_or_assign(named, std::move(file));
    return named;
  }

  std::optional<std::string> read(const fs::path& file, const char* what) override {
    ConfinedFile self;
    const ConfinedFile* confined = nullptr;
    if (const auto found = located_.find(file); found != located_.end()) {
      confined = &found->second;
    } else {
      // A model, as the job named it (job paths may be absolute).
      self = confine_file(root_, file, file.string(), ReferenceForm::relative_or_absolute);
      if (self.verdict == Confinement::missing) throw InputError(file.string() + ": cannot read the model file");
      if (!self.allowed()) throw InputError(file.string() + ": " + self.reason);
      confined = &self;
    }
    std::string bytes, why;
    if (!read_confined(*confined, bytes, &why)) {
      throw InputError(fmt::format("{}: cannot read the {}: {}", confined->named.string(), what, why));
    }
    return bytes;
  }

  const ConfinedFile& located(const fs::path& named) const { return located_.at(named); }

 private:
  fs::path root_;
  std::map<fs::path, ConfinedFile> located_;  // by name: every file locate allowed
};

ModelDependencyScanner::ModelDependencyScanner(fs::path asset_root)
    : disk_(std::make_unique<OnDisk>(fs::weakly_canonical(fs::absolute(asset_root)))), scanner_(*disk_) {}

ModelDependencyScanner::~ModelDependencyScanner() = default;

const std::vector<ConfinedFile>& ModelDependencyScanner::dependencies(const fs::path& model) {
  const fs::path key = model.lexically_normal();
  if (const auto found = models_.find(key); found != models_.end()) return found->second;
  // On disk every file is read or refused, so a model is always scanned whole.
  std::vector<ConfinedFile> files;
  for (const fs::path& named : scanner_.references(key)) files.push_back(disk_->located(named));
  return models_.emplace(key, std::move(files)).first->second;
}

std::vector<ConfinedFile> model_dependencies(const fs::path& model) {
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(fs::absolute(model), ec);
  ModelDependencyScanner scanner(resolved.parent_path());
  return scanner.dependencies(resolved);
}

}  // namespace farm
