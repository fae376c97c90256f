#pragma once
// How the JPEG reader and writer take libjpeg's errors: its default error_exit ends the process;
// ours longjmps back below a setjmp in a frame that holds nothing with a destructor, the message
// kept in plain storage for the C++ side to throw.
#include <csetjmp>
#include <cstddef>
#include <cstdio>  // jpeglib.h needs FILE and size_t declared before it
#include <jpeglib.h>

namespace farm {

struct JpegError {
  jpeg_error_mgr manager{};
  std::jmp_buf jump{};
  char message[JMSG_LENGTH_MAX] = "";
};

inline void on_jpeg_error(j_common_ptr cinfo) {
  auto* error = static_cast<JpegError*>(cinfo->client_data);
  (*cinfo->err->format_message)(cinfo, error->message);
  std::longjmp(error->jump, 1);
}

}  // namespace farm
