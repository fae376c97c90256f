#pragma once
// farm.v1 messages as JSON (protobuf's JSON mapping, with the .proto's field names and every
// field, defaults too): what `farm ... --json` prints and the dashboard's API speaks.
#include <google/protobuf/message.h>

#include <string>
#include <string_view>

namespace farm {

std::string json_of(const google::protobuf::Message& message);
// Fills `message` from `json`; InputError naming `what` and the parser's complaint.
void parse_json(std::string_view json, google::protobuf::Message& message, std::string_view what);

}  // namespace farm
