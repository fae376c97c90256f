#include "renderer/image/preview.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <immintrin.h>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "renderer/image/jpeg_writer.h"
#include "renderer/util/atomic_file.h"
#include "renderer/image/png_writer.h"
#include "renderer/image/rgb8_image.h"
#include "renderer/util/cpu_features.h"
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
// values, under one code even where the curve is steepest, so at most kSteps = 1 of them (the
// constructor checks it, and the test Srgb.PreviewEncodingIsToSrgb8ForEveryFloatAroundEachStep
// checks every float around every step, and fails with none). The steps are taken without
// branches, and NaN, negative and out-of-range inputs are folded into the run index the same way:
// a frame's edges made the branches mispredict, and the preview of a 640x480 frame took 2.4 ms.
// For eight lanes at once (AVX2, which gathers one table entry a lane), each run's entry also
// comes packed with its step: the run's first code from bit 17 up, and where in the run the code
// steps up in the low bits (65536 when it does not).
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
      const auto run_of = [&](unsigned c) { return std::bit_cast<std::uint32_t>(steps_[c]) >> 16; };
      if (code + 2 <= 255 && run_of(code + 2) == run) {
        throw std::logic_error("Srgb8Table: two code steps within one run of 65536 floats");
      }
      const std::uint32_t step_at =
          code < 255 && run_of(code + 1) == run ? (std::bit_cast<std::uint32_t>(steps_[code + 1]) & 0xFFFFu) : 0x10000u;
      packed_[run] = code << 17 | step_at;
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

  // Per run: code << 17 | where in the run the code steps up (65536: nowhere).
  const std::uint32_t* packed() const { return packed_.data(); }

  static constexpr std::uint32_t kOne = 0x3F800000u;       // 1.0f
  static constexpr std::uint32_t kInfinity = 0x7F800000u;  // +inf

 private:
  static constexpr unsigned kSteps = 1;
  std::array<float, 256 + kSteps> steps_{};                 // steps_[c]: the least input of code c
  std::array<std::uint8_t, (kOne >> 16) + 1> runs_{};
  std::array<std::uint32_t, (kOne >> 16) + 1> packed_{};
};

const Srgb8Table& srgb8_table() {
  static const Srgb8Table table;
  return table;
}

// `count` pixels of a film row from `c` into `at` (3 bytes a pixel), by the table, a channel at a time.
void convert_pixels(const glm::vec4* c, int count, std::uint8_t* at) {
  const Srgb8Table& encode = srgb8_table();
  for (int i = 0; i < count; ++i, ++c, at += 3) {
    at[0] = encode(c->x);
    at[1] = encode(c->y);
    at[2] = encode(c->z);
  }
}

// The table's arithmetic on eight channels at once with AVX2, lane by lane (the clamp as compares
// and an unsigned min, the entries gathered): the codes to_srgb8 gives them, one a 32-bit lane.
__attribute__((target("avx2"))) __m256i srgb8_codes_avx2(const float* channels, const int* entries) {
  const __m256i bits = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(channels));
  const __m256i positive =
      _mm256_andnot_si256(_mm256_cmpgt_epi32(bits, _mm256_set1_epi32(static_cast<int>(Srgb8Table::kInfinity))),
                          _mm256_cmpgt_epi32(bits, _mm256_setzero_si256()));
  const __m256i clamped =
      _mm256_and_si256(_mm256_min_epu32(bits, _mm256_set1_epi32(static_cast<int>(Srgb8Table::kOne))), positive);
  const __m256i entry = _mm256_i32gather_epi32(entries, _mm256_srli_epi32(clamped, 16), 4);
  // low >= step_at, both below 2^17: not (step_at > low).
  const __m256i past = _mm256_andnot_si256(_mm256_cmpgt_epi32(_mm256_and_si256(entry, _mm256_set1_epi32(0x1FFFF)),
                                                              _mm256_and_si256(clamped, _mm256_set1_epi32(0xFFFF))),
                                           _mm256_set1_epi32(1));
  return _mm256_add_epi32(_mm256_srli_epi32(entry, 17), past);
}

// convert_pixels four pixels (16 channels, alpha's encoded and dropped) at a time. A row's bytes
// are written exactly (8 + 4 a group): rows of one film are converted by several threads at once,
// and a wider store would reach into the next one's.
__attribute__((target("avx2"))) void convert_pixels_avx2(const glm::vec4* c, int count, std::uint8_t* at) {
  const int* entries = reinterpret_cast<const int*>(srgb8_table().packed());
  // Byte order after the packs (each 128-bit half on its own): the dwords hold pixels 0, 2 | 1, 3.
  const __m256i pixel_order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
  const __m128i drop_alpha = _mm_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1);
  int i = 0;
  for (; i + 4 <= count; i += 4, c += 4, at += 12) {
    const __m256i first = srgb8_codes_avx2(&c[0].x, entries), second = srgb8_codes_avx2(&c[2].x, entries);  // 0-1, 2-3
    const __m256i words = _mm256_packus_epi32(first, second);         // codes fit 16 bits, and 8
    const __m256i bytes = _mm256_permutevar8x32_epi32(_mm256_packus_epi16(words, words), pixel_order);
    const __m128i rgb = _mm_shuffle_epi8(_mm256_castsi256_si128(bytes), drop_alpha);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(at), rgb);
    const int last = _mm_cvtsi128_si32(_mm_srli_si128(rgb, 8));
    std::memcpy(at + 8, &last, 4);
  }
  convert_pixels(c, count - i, at);
}

// Rows [y0, y1) of the film (counted from its rect's top) into `pixels`, which holds the whole film.
void convert_rows(const TileBuffer& image, int y0, int y1, std::uint8_t* pixels, Srgb8Encoder encoder) {
  const Rect& r = image.rect();
  const bool avx2 = encoder == Srgb8Encoder::Best && cpu_has_avx2();
  std::uint8_t* at = pixels + static_cast<std::size_t>(y0) * static_cast<std::size_t>(r.width()) * 3;
  for (int y = r.y0 + y0; y < r.y0 + y1; ++y, at += static_cast<std::size_t>(r.width()) * 3) {
    if (avx2) {
      convert_pixels_avx2(&image.rgba(r.x0, y), r.width(), at);
    } else {
      convert_pixels(&image.rgba(r.x0, y), r.width(), at);
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

Rgb8Image to_srgb8_image(const TileBuffer& image, Srgb8Encoder encoder) {
  Rgb8Image out = sized_for(image);
  convert_rows(image, 0, image.rect().height(), out.pixels.data(), encoder);
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
  convert_rows(film_, y0, y1, pixels_.begin(), Srgb8Encoder::Best);
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
