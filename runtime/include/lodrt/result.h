#pragma once
// Result codes shared by every lodrt entry point (cgltf's cgltf_result style): Ok is 0, and each kind
// of bad input has its own code so a caller can tell truncation from corruption.

#include <cstdint>

#include "lodrt/export.h"

namespace lodrt {

enum class Result : int {
    Ok = 0,
    InvalidArgument,    // null pointer or contradictory options: a caller bug, not bad input
    Truncated,          // the input ends before a length field says it should
    BadMagic,           // neither a GLB header nor JSON text
    UnsupportedVersion, // GLB container version other than 2, or glTF asset.version not 2.x
    BadChunk,           // GLB chunk missing, duplicated, out of order, misaligned or of zero length
    TrailingBytes,      // bytes after the end announced by the GLB header
    BadJson,            // JSON syntax error (including invalid escapes and duplicate object keys)
    BadUtf8,            // a JSON string is not valid UTF-8 (overlong, surrogate, > U+10FFFF, cut off)
    JsonTooDeep,        // nesting deeper than JsonLimits::max_depth
    JsonTooLarge,       // more values than JsonLimits::max_nodes or a longer string than max_string_length
    NumberOutOfRange,   // a JSON number whose magnitude does not fit a double (e.g. 1e400)
    OutOfMemory,        // the allocator returned null
    BadGltf,            // the JSON is valid but breaks a glTF 2.0 rule (wrong type, missing property, bad index)
    OutOfBounds,        // an accessor, buffer view or index points outside the bytes that exist
    BadStructure,       // PFRep: an entry breaks an ordering rule (dependency cycle, degenerate fan, bad count)
    BufferTooSmall,     // a caller-owned output buffer is smaller than the result
    CorruptStream,      // a compressed stream decodes to something impossible (index out of range, overrun)
    NotLoaded,          // PFRep prefix: the request needs bytes that have not been loaded yet
};

/// Stable name of a result code, e.g. "Truncated"; "Unknown" for values outside the enum.
LODRT_API const char* resultName(Result result);

} // namespace lodrt
