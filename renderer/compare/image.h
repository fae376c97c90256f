#pragma once
// An image as the comparison metrics see it: float channels exactly as stored, any channel set.
// EXR channels keep their names and values (half widened to float); an 8-bit PNG or JPEG holds
// its stored values scaled to [0, 1] (sRGB-encoded, as `idiff` reads them), channels R G B
// (and A), or Y for a grey image.
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <cstdint>
#include <vector>

namespace farm {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::string> channels;  // EXR names: R G B A Z N.X ... variance.R ...
  std::vector<float> values;          // interleaved: ((y * width) + x) * channels.size() + c
  bool display_referred = false;      // true for PNG/JPEG: sRGB-encoded values, not linear

  std::size_t pixel_count() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
  std::size_t channel_count() const { return channels.size(); }
  // The index of the channel called `name`, or -1.
  int channel(std::string_view name) const;
  float at(int x, int y, int c) const {
    return values[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) *
                      channels.size() +
                  static_cast<std::size_t>(c)];
  }
  float& at(int x, int y, int c) {
    return values[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) *
                      channels.size() +
                  static_cast<std::size_t>(c)];
  }
};

// A blank image of the given size and channels, every value 0.
Image make_image(int width, int height, std::vector<std::string> channels);

// An image compared may hold at most this many pixels: 8192 x 8192, 1 GiB as RGBA floats. A
// 1 MB PNG can declare 16384 x 16384 and decode to 5 GB (issue #32); its header is refused instead.
inline constexpr std::uint64_t kMaxComparedPixels = std::uint64_t{1} << 26;

// An image's size and kind from its header alone: width, height and display_referred set, no
// channels and no values; nothing decoded. Throws InputError as read_image does.
Image read_image_header(const std::filesystem::path& file);

// Reads an EXR (every channel of its first part, as float), a PNG (8 or 16 bit) or a JPEG by
// its contents, not its extension. Throws InputError naming the file on a missing or unreadable
// file, and refuses images wider or taller than `max_side` (job_limits' bound by default) or of
// more than kMaxComparedPixels from their header, before their pixels are decoded, so a hostile
// header cannot make it allocate gigabytes.
Image read_image(const std::filesystem::path& file, int max_side = 0);

// A reference and a new image to compare: their headers first, and when their sizes differ
// the headers only (compare_images says so without a pixel decoded), else both read whole.
std::pair<Image, Image> read_images_to_compare(const std::filesystem::path& reference,
                                               const std::filesystem::path& test);

// The colour channels a metric compares: R G B when present, else Y (grey). Empty when neither.
std::vector<int> colour_channels(const Image& image);

// Writes an 8-bit RGB PNG of channels R G B (or a single channel as grey) of `image`, each value
// clamped to [0, 1] and stored as is (no transfer function: diff maps are already display
// values). Written to a temporary file and renamed into place.
void write_png_image(const Image& image, const std::filesystem::path& file);

// What a person looks at: the colour channels as R G B display values. An 8-bit image's stored
// (sRGB-encoded) values as they are; a linear image's clamped to [0, 1] and sRGB-encoded, as
// previews are.
Image to_display(const Image& image);

// Writes every channel of `image` to an EXR as 32-bit float, atomically.
void write_exr_image(const Image& image, const std::filesystem::path& file);

}  // namespace farm
