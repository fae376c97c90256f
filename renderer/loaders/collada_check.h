#pragma once
// Assimp's COLLADA reader trusts a file's numbers the way its PLY reader trusts a header: it
// reserves what a `count` attribute says before reading the values, and it reads a <p> index list
// in a loop that only stops at the end of the text, so one character in it that is not a digit
// (`66z34`) is read as an index again and again without moving on: a 10 kB file grew a process
// past 12 GB. So before Assimp sees a .dae file, the lists it reads are checked here:
//   - <p>, <v>, <vcount> and <h> hold only non-negative integers and whitespace;
//   - an array's `count` (<float_array>, <int_array>, ...) is no more than the values it holds;
//   - a primitive element's `count` (<triangles>, <polylist>, ...) is no more than the numbers of
//     its index lists, since every primitive takes at least one;
//   - a <polylist>'s corners (its <vcount> summed) are no more than the indices of its <p>, since
//     every corner takes at least one (Assimp reserves them all first).
// Each failure is an InputError naming the file, the element and its line.
#include <string>
#include <string_view>

#include "renderer/util/confined_file.h"

namespace farm {

// Checks the COLLADA document `text`; `file` names it in messages.
void check_collada_text(std::string_view text, const std::string& file);

// The same for an allowed file, read whole (its size is within the job's limits already).
void check_collada_file(const ConfinedFile& file, const std::string& name);

}  // namespace farm
