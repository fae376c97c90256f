#pragma once
// A C stdio FILE that closes itself: the one owner type for the libraries that want a FILE*
// (libpng, libjpeg) and for reading a file's header bytes.
#include <cstdio>
#include <memory>

namespace farm {

struct CFileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using CFile = std::unique_ptr<std::FILE, CFileCloser>;

}  // namespace farm
