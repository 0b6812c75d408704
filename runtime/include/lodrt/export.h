#pragma once
// LODRT_API marks the public symbols; shared builds use hidden visibility for everything else.

#if defined(LODRT_SHARED_BUILD)
#if defined(_WIN32)
#if defined(LODRT_BUILDING)
#define LODRT_API __declspec(dllexport)
#else
#define LODRT_API __declspec(dllimport)
#endif
#else
#define LODRT_API __attribute__((visibility("default")))
#endif
#else
#define LODRT_API
#endif
