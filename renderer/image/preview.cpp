#include "renderer/image/preview.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "renderer/image/jpeg_writer.h"
#include "renderer/util/atomic_file.h"
#include "renderer/image/png_writer.h"
#include "renderer/image/rgb8_image.h"
#include "renderer/util/file_extension.h"

namespace farm {
namespace {

enum class PreviewFormat { Png, Jpeg };

// The extensions OpenImageIO, which wrote previews before, took for these two formats.
std::optional<PreviewFormat> preview_format(const std::filesystem::path& file) {
  const std::string extension = lowercase_extension(file);
  if (extension == ".png") return PreviewFormat::Png;
  constexpr std::array<std::string_view, 6> jpeg = {".jpg", ".jpeg", ".jpe", ".jif", ".jfif", ".jfi"};
  if (std::find(jpeg.begin(), jpeg.end(), extension) != jpeg.end()) return PreviewFormat::Jpeg;
  return std::nullopt;
}

// to_srgb8 by table, exactly: the 255 smallest inputs at which the 8-bit code steps up, found
// once by bisection over the floats in [0, 1] on to_srgb8 itself (it rises monotonically), and
// for each run of 65536 floats sharing their top 16 bits the code of the first one. A value's
// code is its run's, stepped up past the thresholds it reaches: a run spans under 1% of its
// values, under one code even where the curve is steepest, so at most kSteps = 1 of them (the test
// Srgb.PreviewEncodingIsToSrgb8ForEveryFloatAroundEachStep checks every float around every step,
// and fails with none). The steps are taken without branches, and NaN,
// negative and out-of-range inputs are folded into the run index the same way: a frame's edges
// made the branches mispredict, and the preview of a 640x480 frame took 2.4 ms.
class Srgb8Table {
 public:
  Srgb8Table() {
    for (int code = 1; code <= 255; ++code) {
      std::uint32_t lo = 0, hi = kOne;  // floats >= 0 order like their bit patterns
      while (lo < hi) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        if (to_srgb8(std::bit_cast<float>(mid)) >= code) hi = mid; else lo = mid + 1;
      }
      steps_[static_cast<std::size_t>(code)] = std::bit_cast<float>(lo);
    }
    // Past 255: never reached. steps_[0] (code 0's least input) is never compared.
    for (std::size_t c = 256; c < steps_.size(); ++c) steps_[c] = std::numeric_limits<float>::infinity();
    // A run's first code, read off the steps (runs and steps both rise with the bits).
    unsigned code = 0;
    for (std::uint32_t run = 0; run < runs_.size(); ++run) {
      while (code < 255 && std::bit_cast<float>(run << 16) >= steps_[code + 1]) ++code;
      runs_[run] = static_cast<std::uint8_t>(code);
    }
  }

  std::uint8_t operator()(float linear) const {
    const std::uint32_t bits = std::bit_cast<std::uint32_t>(linear);
    // Zero, negatives and NaN (any sign) to the run of 0.0; 1.0 and above, infinity too, to 1.0's.
    const bool positive = static_cast<std::int32_t>(bits) > 0 && bits <= kInfinity;
    const std::uint32_t clamped = positive ? std::min(bits, kOne) : 0u;
    unsigned code = runs_[clamped >> 16];
    const float value = std::bit_cast<float>(clamped);
    for (unsigned k = 0; k < kSteps; ++k) code += value >= steps_[code + 1] ? 1u : 0u;
    return static_cast<std::uint8_t>(code);
  }

 private:
  static constexpr std::uint32_t kOne = 0x3F800000u;       // 1.0f
  static constexpr std::uint32_t kInfinity = 0x7F800000u;  // +inf
  static constexpr unsigned kSteps = 1;
  std::array<float, 256 + kSteps> steps_{};                 // steps_[c]: the least input of code c
  std::array<std::uint8_t, (kOne >> 16) + 1> runs_{};
};

// Rows [y0, y1) of the film (counted from its rect's top) into `pixels`, which holds the whole film.
void convert_rows(const TileBuffer& image, int y0, int y1, std::uint8_t* pixels) {
  static const Srgb8Table encode;
  const Rect& r = image.rect();
  std::uint8_t* at = pixels + static_cast<std::size_t>(y0) * static_cast<std::size_t>(r.width()) * 3;
  for (int y = r.y0 + y0; y < r.y0 + y1; ++y) {
    const glm::vec4* c = &image.rgba(r.x0, y);
    for (int x = r.x0; x < r.x1; ++x, ++c, at += 3) {
      at[0] = encode(c->x);
      at[1] = encode(c->y);
      at[2] = encode(c->z);
    }
  }
}

Rgb8Image sized_for(const TileBuffer& image) {
  const Rect& r = image.rect();
  Rgb8Image out{r.width(), r.height(), {}};
  out.pixels.resize(static_cast<std::size_t>(r.width()) * static_cast<std::size_t>(r.height()) * 3);
  return out;
}

// The format `file`'s extension names, checked before anything is converted: the error names it.
PreviewFormat checked_format(const TileBuffer& image, const std::filesystem::path& file) {
  if (image.rect().empty()) {
    throw std::invalid_argument(fmt::format("{}: cannot write an empty image", file.string()));
  }
  const std::optional<PreviewFormat> format = preview_format(file);
  if (!format) {
    throw std::runtime_error(fmt::format("{}: cannot write preview: no image writer for '{}' files "
                                         "(PNG: .png, JPEG: .jpg or .jpeg)",
                                         file.string(), file.extension().string()));
  }
  return *format;
}

// The preview's rows to `file`, atomically.
void write_rows(const Rgb8Rows& rows, PreviewFormat format, const std::filesystem::path& file) {
  write_c_file_atomically(file, [&](std::FILE* out) {
    if (format == PreviewFormat::Png) {
      write_png(rows, out, file);
    } else {
      write_jpeg(rows, out, file);
    }
  });
}

}  // namespace

Rgb8Image to_srgb8_image(const TileBuffer& image) {
  Rgb8Image out = sized_for(image);
  convert_rows(image, 0, image.rect().height(), out.pixels.data());
  return out;
}

StreamedPreview::StreamedPreview(const TileBuffer& film, std::filesystem::path file)
    : film_(film),
      file_(std::move(file)),
      png_(checked_format(film, file_) == PreviewFormat::Png),
      width_(film.rect().width()),
      height_(film.rect().height()) {
  pixels_.allocate(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 3);
  if (png_) {
    strips_.emplace(width_, height_, file_);
    strip_rows_ready_.assign(static_cast<std::size_t>(strips_->strips()), 0);
    return;
  }
  ready_.assign(static_cast<std::size_t>(height_), false);
  jpeg_encoder_ = std::thread([this] {
    try {
      write_rows({width_, height_,
                  [this](int y) {
                    std::unique_lock lock(mutex_);
                    changed_.wait(lock, [&] { return y < leading_ || abandoned_; });
                    if (y >= leading_) throw rows_never_came();
                    return row(y);
                  }},
                 PreviewFormat::Jpeg, file_);
    } catch (...) {
      jpeg_failure_ = std::current_exception();
    }
  });
}

StreamedPreview::~StreamedPreview() {
  if (jpeg_encoder_.joinable()) {
    abandon();
    jpeg_encoder_.join();
  }
}

void StreamedPreview::convert(int y0, int y1) {
  convert_rows(film_, y0, y1, pixels_.begin());
  if (!png_) {
    {
      std::lock_guard lock(mutex_);
      for (int y = y0; y < y1; ++y) ready_[static_cast<std::size_t>(y)] = true;
      while (leading_ < static_cast<int>(ready_.size()) && ready_[static_cast<std::size_t>(leading_)]) ++leading_;
    }
    changed_.notify_all();
    return;
  }
  // The strips these rows complete are compressed here, while their rows are in this core's cache.
  std::vector<int> complete;
  {
    std::lock_guard lock(mutex_);
    for (int y = y0; y < y1; ++y) {
      const int strip = y / PngStrips::kRows;
      int& ready = strip_rows_ready_[static_cast<std::size_t>(strip)];
      if (++ready == strips_->end_row(strip) - strips_->first_row(strip)) complete.push_back(strip);
    }
  }
  for (int strip : complete) {
    try {
      strips_->compress(strip, [this](int y) { return row(y); });
    } catch (...) {
      {
        std::lock_guard lock(mutex_);
        if (!strip_failure_) strip_failure_ = std::current_exception();
      }
      changed_.notify_all();
      throw;
    }
    {
      std::lock_guard lock(mutex_);
      ++strips_done_;
    }
    changed_.notify_all();
  }
}

void StreamedPreview::abandon() {
  {
    std::lock_guard lock(mutex_);
    abandoned_ = true;
  }
  changed_.notify_all();
}

const std::uint8_t* StreamedPreview::row(int y) const {
  return pixels_.begin() + static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) * 3;
}

std::runtime_error StreamedPreview::rows_never_came() const {
  return std::runtime_error(fmt::format("{}: the preview's rows never came", file_.string()));
}

void StreamedPreview::finish() {
  if (!png_) {
    jpeg_encoder_.join();
    if (jpeg_failure_) std::rethrow_exception(jpeg_failure_);
    return;
  }
  {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return strips_done_ == strips_->strips() || strip_failure_ || abandoned_; });
    if (strip_failure_) std::rethrow_exception(strip_failure_);
    if (strips_done_ < strips_->strips()) throw rows_never_came();
  }
  write_c_file_atomically(file_, [&](std::FILE* out) { strips_->write(out); });
}

float linear_to_srgb(float linear) {
  if (std::isnan(linear)) return 0.0f;  // NaN shows as black, not as garbage
  const float c = std::clamp(linear, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

std::uint8_t to_srgb8(float linear) {
  return static_cast<std::uint8_t>(std::lround(linear_to_srgb(linear) * 255.0f));
}

bool preview_format_supported(const std::filesystem::path& file) { return preview_format(file).has_value(); }

void write_preview(const TileBuffer& image, const std::filesystem::path& file) {
  const PreviewFormat format = checked_format(image, file);
  const Rgb8Image pixels = to_srgb8_image(image);
  write_rows(rows_of(pixels), format, file);
}

}  // namespace farm
