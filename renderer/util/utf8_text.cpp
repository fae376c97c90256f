#include "renderer/util/utf8_prefix.h"

namespace farm {

std::string utf8_prefix(const std::string& text, std::size_t max_bytes) {
  if (text.size() <= max_bytes) return text;
  std::size_t cut = max_bytes;
  // A byte 10xxxxxx continues the character before it: the cut goes back to where one starts.
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0u) == 0x80u) --cut;
  return text.substr(0, cut);
}

}  // namespace farm
