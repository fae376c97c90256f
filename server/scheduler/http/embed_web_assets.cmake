# cmake -DWEB_DIR=server/web -DOUTPUT=web_assets_data.cpp -P embed_web_assets.cmake
# Writes a C++ file holding every file of WEB_DIR as bytes, with find_web_asset() over them
# (server/scheduler/http/web_assets.h). Bytes, not string literals: no file can end the literal.
file(GLOB names RELATIVE "${WEB_DIR}" "${WEB_DIR}/*")
list(SORT names)
set(arrays "")
set(entries "")
set(i 0)
foreach(name IN LISTS names)
  if(IS_DIRECTORY "${WEB_DIR}/${name}")
    continue()
  endif()
  file(READ "${WEB_DIR}/${name}" hex HEX)
  string(LENGTH "${hex}" digits)
  math(EXPR size "${digits} / 2")
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
  get_filename_component(ext "${name}" LAST_EXT)
  if(ext STREQUAL ".html")
    set(type "text/html; charset=utf-8")
  elseif(ext STREQUAL ".js")
    set(type "text/javascript; charset=utf-8")
  elseif(ext STREQUAL ".css")
    set(type "text/css; charset=utf-8")
  elseif(ext STREQUAL ".svg")
    set(type "image/svg+xml")
  else()
    set(type "application/octet-stream")
  endif()
  string(APPEND arrays "const unsigned char kFile${i}[] = {${bytes}0};\n")
  string(APPEND entries "    {\"${name}\", \"${type}\", {reinterpret_cast<const char*>(kFile${i}), ${size}}},\n")
  math(EXPR i "${i} + 1")
endforeach()
file(WRITE "${OUTPUT}.tmp" "// Generated from server/web by embed_web_assets.cmake: do not edit.
#include \"server/scheduler/http/web_assets.h\"

namespace farm {
namespace {
${arrays}
const WebAsset kAssets[] = {
${entries}};
}  // namespace

const WebAsset* find_web_asset(std::string_view name) {
  for (const WebAsset& a : kAssets) {
    if (a.name == name) return &a;
  }
  return nullptr;
}

}  // namespace farm
")
# Only a change of content touches the output, so an unchanged page rebuilds nothing.
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUTPUT}.tmp")
