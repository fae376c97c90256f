#pragma once
// The image files a COLLADA document names, found with an XML parser (pugixml) so that comments,
// CDATA, entities and namespace prefixes read as the model loader reads them. Both schemas:
//   1.4  <image id="skin"><init_from>skin.png</init_from></image>
//   1.5  <image id="skin"><init_from><ref>skin.png</ref></init_from></image>
// 1.5 also nests <init_from> in <create_2d>/<create_3d>/<create_cube> under <image>, and may hold
// the pixels themselves in <hex>, which names no file. An <init_from> outside <image> (a 1.4
// <surface>'s) names an image by its id, not a file.
#include <string>
#include <vector>

namespace farm {

// The URIs as written (entities decoded; not trimmed, not percent-decoded), in document order.
// Empty when `xml` is not well-formed: the model loader reports the syntax error, with its own
// message, when the job renders; a guess here would only add a worse one. `xml` is parsed in
// place, hence taken by value.
std::vector<std::string> collada_image_uris(std::string xml);

}  // namespace farm
