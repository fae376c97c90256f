#include "server/grade/similar_submissions.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <map>
#include <optional>
#include <tuple>
#include <utility>

#include "renderer/compare/flip.h"
#include "renderer/compare/image.h"
#include "server/common/markup_escape.h"
#include "renderer/util/atomic_file.h"
#include "server/common/sha256.h"
#include "server/grade/csv_field.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr int kThumbnailSize = 16;

// The thumbnail: R G B box means of kThumbnailSize x kThumbnailSize cells (fewer cells hold
// pixels when the image is smaller than that; those stay 0).
std::vector<float> make_thumbnail(const Image& display) {
  constexpr std::size_t kCells = static_cast<std::size_t>(kThumbnailSize) * kThumbnailSize;
  std::vector<double> sum(kCells * 3, 0.0);
  std::vector<std::size_t> count(kCells, 0);
  for (int y = 0; y < display.height; ++y) {
    const int ty = y * kThumbnailSize / display.height;
    for (int x = 0; x < display.width; ++x) {
      const auto cell = static_cast<std::size_t>(ty * kThumbnailSize + x * kThumbnailSize / display.width);
      ++count[cell];
      for (int c = 0; c < 3; ++c) sum[cell * 3 + static_cast<std::size_t>(c)] += display.at(x, y, c);
    }
  }
  std::vector<float> thumbnail(kCells * 3, 0.0f);
  for (std::size_t i = 0; i < thumbnail.size(); ++i)
    if (count[i / 3] > 0) thumbnail[i] = static_cast<float>(sum[i] / static_cast<double>(count[i / 3]));
  return thumbnail;
}

// The mean absolute difference over the cells that hold pixels (the same for images of one size).
double distance(const std::vector<float>& a, const std::vector<float>& b, int width, int height) {
  double total = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) total += std::fabs(static_cast<double>(a[i]) - b[i]);
  const int cells = std::min(width, kThumbnailSize) * std::min(height, kThumbnailSize);
  return cells > 0 ? total / (3.0 * cells) : 0.0;
}

// The pixels as a person sees them: R G B display values (to_display), whatever the PNG held.
Image display_image(const fs::path& png) { return to_display(read_image(png)); }

// Display values at 8 bits (what a PNG holds; a 16-bit PNG loses what no screen shows): a quarter
// of the memory of floats, kept for every student in a pair that passed the thumbnail.
struct Pixels {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
};

Pixels pixels_of(const Image& display) {
  Pixels p{display.width, display.height, std::vector<std::uint8_t>(display.values.size())};
  for (std::size_t i = 0; i < display.values.size(); ++i)
    p.rgb[i] = static_cast<std::uint8_t>(std::lround(std::clamp(display.values[i], 0.0f, 1.0f) * 255.0f));
  return p;
}

Image image_of(const Pixels& p) {
  Image image = make_image(p.width, p.height, {"R", "G", "B"});
  for (std::size_t i = 0; i < p.rgb.size(); ++i) image.values[i] = static_cast<float>(p.rgb[i]) / 255.0f;
  image.display_referred = true;
  return image;
}

double pixel_distance(const Pixels& a, const Pixels& b) {
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i)
    total += static_cast<std::uint64_t>(std::abs(static_cast<int>(a.rgb[i]) - static_cast<int>(b.rgb[i])));
  return a.rgb.empty() ? 0.0 : static_cast<double>(total) / (255.0 * static_cast<double>(a.rgb.size()));
}

std::string pixel_hash(const Image& display) {
  Sha256 sha;
  sha.update(fmt::format("{}x{}:", display.width, display.height));
  sha.update(display.values.data(), display.values.size() * sizeof(float));
  return sha.finish_hex();
}

struct Signature {
  std::string student;
  fs::path png;
  int width = 0, height = 0;
  std::string hash;
  std::vector<float> thumbnail;
};

std::optional<Signature> signature_of(const std::string& student, const fs::path& png) {
  try {
    const Image display = display_image(png);
    return Signature{student, png, display.width, display.height, pixel_hash(display), make_thumbnail(display)};
  } catch (const std::exception&) {
    return std::nullopt;  // unreadable: the runner has scored it already; nothing to compare
  }
}

std::vector<std::string> file_tasks(const ClassGrades& grades) {
  std::vector<std::string> tasks;
  if (grades.rubric != nullptr) {
    for (const GradeTask& t : grades.rubric->tasks)
      if (t.file) tasks.push_back(t.name);
  } else if (!grades.students.empty()) {
    for (const TaskGrade& t : grades.students.front().tasks) tasks.push_back(t.task);
  }
  return tasks;
}

}  // namespace

double thumbnail_distance(const Image& a, const Image& b) {
  return distance(make_thumbnail(a), make_thumbnail(b), a.width, a.height);
}

double pixel_distance(const Image& a, const Image& b) {
  double total = 0.0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x)
      for (int c = 0; c < 3; ++c) total += std::fabs(static_cast<double>(a.at(x, y, c)) - b.at(x, y, c));
  return a.pixel_count() > 0 ? total / (3.0 * static_cast<double>(a.pixel_count())) : 0.0;
}

std::vector<SimilarPair> find_similar_submissions(const ClassGrades& grades, const SimilarityOptions& options,
                                                  SimilarityCounts* counts) {
  SimilarityCounts local;
  SimilarityCounts& count = counts != nullptr ? *counts : local;
  count = {};
  std::vector<SimilarPair> pairs;
  std::map<fs::path, std::string> reference_hashes;  // one decode per reference file
  const auto reference_hash = [&](const fs::path& png) -> const std::string& {
    auto [it, added] = reference_hashes.try_emplace(png);
    if (added) {
      try {
        it->second = pixel_hash(display_image(png));
      } catch (const std::exception&) {
        it->second.clear();
      }
    }
    return it->second;
  };

  for (const std::string& task : file_tasks(grades)) {
    // 1. One signature per student's image.
    std::vector<Signature> signatures;
    for (const StudentGrade& s : grades.students) {
      const auto t = std::find_if(s.tasks.begin(), s.tasks.end(), [&](const TaskGrade& g) { return g.task == task; });
      if (t == s.tasks.end() || t->student_png.empty()) continue;
      std::optional<Signature> sig = signature_of(s.student, t->student_png);
      if (!sig) continue;
      if (options.skip_reference_matches && !t->reference_png.empty() && sig->hash == reference_hash(t->reference_png))
        continue;
      signatures.push_back(std::move(*sig));
    }
    count.images += signatures.size();
    std::sort(signatures.begin(), signatures.end(),
              [](const Signature& a, const Signature& b) { return a.student < b.student; });

    // 2. Identical by hash; the thumbnail picks the pairs worth a closer look.
    std::vector<SimilarPair> found;
    std::vector<std::pair<std::size_t, std::size_t>> candidates;
    for (std::size_t i = 0; i < signatures.size(); ++i) {
      for (std::size_t j = i + 1; j < signatures.size(); ++j) {
        const Signature &a = signatures[i], &b = signatures[j];
        if (a.width != b.width || a.height != b.height) continue;
        ++count.pairs;
        if (a.hash == b.hash) {
          ++count.identical;
          found.push_back({task, a.student, b.student, 0.0, true});
        } else if (distance(a.thumbnail, b.thumbnail, a.width, a.height) <= options.thumbnail_tolerance) {
          candidates.emplace_back(i, j);
        }
      }
    }

    count.thumbnail += candidates.size();
    // 3. The pixels of the students in those pairs; their mean difference picks what FLIP sees.
    std::map<std::size_t, std::optional<Pixels>> pixels;
    for (const auto& [i, j] : candidates) {
      pixels.try_emplace(i);
      pixels.try_emplace(j);
    }
    for (auto& [index, p] : pixels) {
      try {
        p = pixels_of(display_image(signatures[index].png));
      } catch (const std::exception&) {
        // An image that read once and not again: its pairs are left out.
      }
    }
    for (const auto& [i, j] : candidates) {
      const std::optional<Pixels>& a = pixels[i];
      const std::optional<Pixels>& b = pixels[j];
      if (!a || !b || a->width != b->width || a->height != b->height) continue;
      if (pixel_distance(*a, *b) > options.pixel_tolerance) continue;
      // 4. FLIP on what is left.
      ++count.flip;
      // Only "below the threshold?" matters: FLIP may stop once the mean is known to be above it.
      FlipOptions flip_options;
      flip_options.stop_when_mean_exceeds = options.flip_threshold;
      const double mean = flip_ldr(image_of(*a), image_of(*b), flip_options, options.pool).mean;
      if (mean < options.flip_threshold)
        found.push_back({task, signatures[i].student, signatures[j].student, mean, false});
    }
    std::sort(found.begin(), found.end(), [](const SimilarPair& a, const SimilarPair& b) {
      return std::tie(a.flip_mean, a.student_a, a.student_b) < std::tie(b.flip_mean, b.student_a, b.student_b);
    });
    pairs.insert(pairs.end(), found.begin(), found.end());
  }
  return pairs;
}

std::string similar_csv(const std::vector<SimilarPair>& pairs) {
  std::string csv = csv_record({"task", "student_a", "student_b", "flip_mean", "identical"});
  for (const SimilarPair& p : pairs)
    csv += csv_record({p.task, p.student_a, p.student_b, format_figure(p.flip_mean), p.identical ? "1" : "0"});
  return csv;
}

std::vector<SimilarPair> write_similar_submissions(const ClassGrades& grades, const fs::path& dir,
                                                   const SimilarityOptions& options, SimilarityCounts* counts) {
  std::vector<SimilarPair> pairs = find_similar_submissions(grades, options, counts);
  write_text_atomically(dir / "similar.csv", similar_csv(pairs));
  return pairs;
}

}  // namespace farm
