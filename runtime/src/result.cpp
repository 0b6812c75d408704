#include "lodrt/result.h"

namespace lodrt {

const char* resultName(Result result) {
    switch (result) {
    case Result::Ok:
        return "Ok";
    case Result::InvalidArgument:
        return "InvalidArgument";
    case Result::Truncated:
        return "Truncated";
    case Result::BadMagic:
        return "BadMagic";
    case Result::UnsupportedVersion:
        return "UnsupportedVersion";
    case Result::BadChunk:
        return "BadChunk";
    case Result::TrailingBytes:
        return "TrailingBytes";
    case Result::BadJson:
        return "BadJson";
    case Result::BadUtf8:
        return "BadUtf8";
    case Result::JsonTooDeep:
        return "JsonTooDeep";
    case Result::JsonTooLarge:
        return "JsonTooLarge";
    case Result::NumberOutOfRange:
        return "NumberOutOfRange";
    case Result::OutOfMemory:
        return "OutOfMemory";
    case Result::BadGltf:
        return "BadGltf";
    case Result::OutOfBounds:
        return "OutOfBounds";
    case Result::BadStructure:
        return "BadStructure";
    case Result::CorruptStream:
        return "CorruptStream";
    case Result::BufferTooSmall:
        return "BufferTooSmall";
    case Result::NotLoaded:
        return "NotLoaded";
    }
    return "Unknown";
}

} // namespace lodrt
