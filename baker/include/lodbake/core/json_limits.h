#pragma once
// A pre-check for JSON from untrusted files (glTF, presets): the nlohmann-json and tinygltf code
// that walks a parsed document recurses once per nesting level, so a few hundred kilobytes of
// "[[[[..." would overflow the stack. Scanning the text first refuses such documents with a clear
// message before any parser sees them.

#include <cstddef>
#include <cstdint>

namespace lodbake {

struct JsonDepthScan {
    bool is_too_deep = false; // some array or object opens at a depth above the limit
    size_t offset = 0;        // is_too_deep: the byte offset of that opening bracket
};

/// Scans `size` bytes of JSON text for '[' and '{' outside strings (escapes honoured) and reports
/// the first one nested deeper than `max_depth` (the top-level value is depth 1). Linear, no
/// allocation; malformed text is left for the parser to report.
JsonDepthScan scanJsonDepth(const uint8_t* data, size_t size, uint32_t max_depth);

} // namespace lodbake
