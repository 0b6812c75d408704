#include "lodbake/core/json_limits.h"

namespace lodbake {

JsonDepthScan scanJsonDepth(const uint8_t* data, size_t size, uint32_t max_depth) {
    JsonDepthScan scan;
    uint64_t depth = 0;
    bool in_string = false;
    for (size_t i = 0; i < size; ++i) {
        const uint8_t c = data[i];
        if (in_string) {
            if (c == '\\')
                ++i; // the escaped character cannot end the string
            else if (c == '"')
                in_string = false;
            continue;
        }
        if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            if (++depth > max_depth) {
                scan.is_too_deep = true;
                scan.offset = i;
                return scan;
            }
        } else if ((c == ']' || c == '}') && depth > 0) {
            --depth;
        }
    }
    return scan;
}

} // namespace lodbake
