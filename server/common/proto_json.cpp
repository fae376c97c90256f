#include "server/common/proto_json.h"

#include <fmt/format.h>
#include <google/protobuf/util/json_util.h>

#include <stdexcept>

#include "renderer/util/input_error.h"

namespace farm {

std::string json_of(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;
  std::string out;
  if (!google::protobuf::util::MessageToJsonString(message, &out, options).ok()) {
    throw std::runtime_error(fmt::format("cannot write a {} as JSON", message.GetTypeName()));
  }
  return out;
}

void parse_json(std::string_view json, google::protobuf::Message& message, std::string_view what) {
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(std::string(json), &message, options);
  if (!status.ok()) {
    throw InputError(fmt::format("{}: not a {} in JSON: {}", what, message.GetTypeName(),
                                 std::string(status.message()).substr(0, 200)));
  }
}

}  // namespace farm
