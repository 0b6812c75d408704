#pragma once
// Decodes the bytes of a glTF "data:application/octet-stream;base64,..." URI (the schema examples
// embed their buffers that way). Returns false when the URI has another form or a bad character.
#include <cstdint>
#include <string>
#include <vector>

namespace lodbake_test {

inline bool dataUriBytes(const std::string& uri, std::vector<uint8_t>& out) {
    const std::string prefix = "data:application/octet-stream;base64,";
    if (uri.compare(0, prefix.size(), prefix) != 0) return false;
    const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    out.clear();
    uint32_t acc = 0;
    int bits = 0;
    for (size_t i = prefix.size(); i < uri.size() && uri[i] != '='; ++i) {
        const size_t v = alphabet.find(uri[i]);
        if (v == std::string::npos) return false;
        acc = (acc << 6) | uint32_t(v);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out.push_back(uint8_t(acc >> bits));
        }
    }
    return true;
}

} // namespace lodbake_test
