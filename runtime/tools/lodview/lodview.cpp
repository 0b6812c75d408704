// lodview: draws a grid of instances of baked packs through lodrt with OpenGL 3.3 core (GLFW
// window, libepoxy for the GL entry points). Interactive: the walk plays in a loop (L toggles LOD /
// forced LOD0, P PFRep refinement, C colour by level, Space pauses, Left/Right step, Esc quits). --headless (under
// xvfb-run with Mesa's llvmpipe on a machine without a GPU): the walk in N frames, a JSON report per
// frame and PNG screenshots. See docs/lodview.md.

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <dlfcn.h>
#include <epoxy/gl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "../tool_module.h"
#include "gl_renderer.h"
#include "../../examples/sample_scene.h"
#include "view_scene.h"

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LODVIEW_LEAK_CHECK 1
#endif
#elif defined(__SANITIZE_ADDRESS__)
#define LODVIEW_LEAK_CHECK 1
#endif
#ifdef LODVIEW_LEAK_CHECK
#include <sanitizer/lsan_interface.h>
#endif

namespace {

using Clock = std::chrono::steady_clock;

constexpr const char* kUsage =
    "usage: lodview PACK.glb... [--headless] [--frames N] [--warmup N] [--size WxH] [--mode lod|lod0|pfrep]\n"
    "               [--colour-by-level] [--budget BYTES] [--threshold PX] [--grid N] [--no-sync] [--pfrep-steps N]\n"
    "               [--report OUT.json] [--screenshot PREFIX] [--shots LIST] [--max-sse PX]\n";

struct Args {
    std::vector<std::string> packs;
    lodview::ViewConfig view;
    bool headless = false;
    bool sync_set = false;
    int frames = 120;
    int warmup = 2;
    std::string report, screenshot;
    std::vector<int> shots; // frame indices; empty = the last frame
    float max_sse = -1;     // check: fail when a drawn level projects above it
};

bool parseInt(const char* text, long lo, long hi, long* out) {
    char* end = nullptr;
    const long v = std::strtol(text, &end, 10);
    if (!*text || *end || v < lo || v > hi) return false;
    *out = v;
    return true;
}

bool parseFloat(const char* text, float* out) {
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (!*text || *end || !(v > 0) || v > 1e9) return false;
    *out = float(v);
    return true;
}

bool parseShots(const char* text, std::vector<int>* out) {
    std::string s(text);
    size_t at = 0;
    while (at <= s.size()) {
        const size_t comma = std::min(s.find(',', at), s.size());
        long v = 0;
        if (!parseInt(s.substr(at, comma - at).c_str(), 0, 1000000, &v)) return false;
        out->push_back(int(v));
        at = comma + 1;
    }
    return !out->empty();
}

// One option with its value at argv[*i + 1]. Returns false (message printed) on a bad value.
bool parseValue(const char* name, const char* value, Args* args) {
    long v = 0;
    bool ok = true;
    if (!std::strcmp(name, "--frames")) {
        ok = parseInt(value, 1, 1000000, &v);
        args->frames = int(v);
    } else if (!std::strcmp(name, "--warmup")) {
        ok = parseInt(value, 0, 1000, &v);
        args->warmup = int(v);
    } else if (!std::strcmp(name, "--pfrep-steps")) {
        ok = parseInt(value, 1, 1000, &v);
        args->view.pfrep_steps = uint32_t(v);
    } else if (!std::strcmp(name, "--grid")) {
        ok = parseInt(value, 1, 100, &v);
        args->view.grid = int(v);
    } else if (!std::strcmp(name, "--size")) {
        unsigned w = 0, h = 0;
        char tail = 0;
        ok = std::sscanf(value, "%ux%u%c", &w, &h, &tail) == 2 && w >= 16 && h >= 16 && w <= 8192 && h <= 8192;
        args->view.width = w;
        args->view.height = h;
    } else if (!std::strcmp(name, "--mode")) {
        ok = !std::strcmp(value, "lod") || !std::strcmp(value, "lod0") || !std::strcmp(value, "pfrep");
        args->view.mode = !std::strcmp(value, "lod0")    ? lodview::LodMode::ForceLod0
                          : !std::strcmp(value, "pfrep") ? lodview::LodMode::Pfrep
                                                         : lodview::LodMode::Lod;
    } else if (!std::strcmp(name, "--budget")) {
        char* end = nullptr;
        args->view.budget_bytes = std::strtoull(value, &end, 10);
        ok = *value && *value != '-' && !*end;
    } else if (!std::strcmp(name, "--threshold")) {
        ok = parseFloat(value, &args->view.pixel_threshold);
    } else if (!std::strcmp(name, "--max-sse")) {
        ok = parseFloat(value, &args->max_sse);
    } else if (!std::strcmp(name, "--report")) {
        args->report = value;
    } else if (!std::strcmp(name, "--screenshot")) {
        args->screenshot = value;
    } else if (!std::strcmp(name, "--shots")) {
        ok = parseShots(value, &args->shots);
    } else {
        std::fprintf(stderr, "lodview: unknown argument %s\n%s", name, kUsage);
        return false;
    }
    if (!ok) std::fprintf(stderr, "lodview: %s: unexpected value %s\n%s", name, value, kUsage);
    return ok;
}

bool parseArgs(int argc, char** argv, Args* args) {
    for (int i = 1; i < argc; ++i) {
        const char* a = argv[i];
        if (a[0] != '-') {
            args->packs.push_back(a);
        } else if (!std::strcmp(a, "--headless")) {
            args->headless = true;
        } else if (!std::strcmp(a, "--colour-by-level")) {
            args->view.colour_by_level = true;
        } else if (!std::strcmp(a, "--no-sync")) {
            args->sync_set = true;
            args->view.sync_streaming = false;
        } else if (i + 1 < argc) {
            if (!parseValue(a, argv[i + 1], args)) return false;
            ++i;
        } else {
            std::fprintf(stderr, "lodview: %s: expected a value\n%s", a, kUsage);
            return false;
        }
    }
    if (args->packs.empty()) {
        std::fprintf(stderr, "%s", kUsage);
        return false;
    }
    // A headless run is a measurement: it draws exactly the selected levels unless told otherwise.
    if (!args->sync_set) args->view.sync_streaming = args->headless;
    return true;
}

using WriteRgb8 = int (*)(const char*, const uint8_t*, uint32_t, uint32_t, char*, size_t);

// The PNG writer is loddump's OpenImageIO module (runtime/tools/png_module.cpp), loaded the same
// way: $LODDUMP_OIIO_MODULE, then the install layout, then beside the executable, then the build tree.
WriteRgb8 loadImageWriter(std::string* error) {
#ifdef LODVIEW_PNG_MODULE_NAME
    WriteRgb8 write = nullptr;
    const auto resolve = [&write](void* handle) {
        write = reinterpret_cast<WriteRgb8>(dlsym(handle, "loddump_write_rgb8"));
        return write != nullptr;
    };
    if (lodtools::openToolModule("LODDUMP_OIIO_MODULE", LODVIEW_PNG_MODULE_NAME, LODVIEW_PNG_MODULE_BUILD_PATH,
                                 "the PNG module (OpenImageIO: loddump_write_rgb8)", resolve, error))
        return write;
#else
    *error = "this lodview was built without OpenImageIO, so --screenshot is not available";
#endif
    return nullptr;
}

// OpenGL clip depth -1..1.
void perspectiveGl(float fov, float aspect, float n, float f, float out[16]) {
    const float t = 1.0f / std::tan(0.5f * fov);
    std::fill(out, out + 16, 0.0f);
    out[0] = t / aspect;
    out[5] = t;
    out[10] = (f + n) / (n - f);
    out[11] = -1;
    out[14] = 2 * f * n / (n - f);
}

const char* modeName(lodview::LodMode mode) {
    return mode == lodview::LodMode::Lod ? "lod" : mode == lodview::LodMode::ForceLod0 ? "lod0" : "pfrep";
}

struct FrameRecord {
    int frame = 0;
    float eye[3] = {};
    double frame_ms = 0, cpu_ms = 0, gpu_ms = 0;
    lodview::FrameStats stats;
};

void writeFrameJson(std::FILE* out, const FrameRecord& r, bool last) {
    const lodview::FrameStats& s = r.stats;
    std::fprintf(out,
                 "    {\"frame\": %d, \"eye\": [%.4f, %.4f, %.4f], \"frame_ms\": %.4f, \"cpu_ms\": %.4f, "
                 "\"gpu_ms\": %.4f, \"cull_ms\": %.5f, \"select_ms\": %.5f, \"stream_ms\": %.5f, "
                 "\"upload_ms\": %.4f, \"decode_ms\": %.4f, \"levels_decoded\": %u, \"decode_growths\": %llu, "
                 "\"stream_wait_ms\": %.4f, \"visible\": %u, \"culled\": %u, "
                 "\"instances_drawn\": %u, \"draw_calls\": %u, \"textured_draw_calls\": %u, \"triangles\": %llu, "
                 "\"levels_resident\": %u, "
                 "\"resident_bytes\": %llu, \"bytes_streamed\": %llu, \"stream_requests\": %u, "
                 "\"lodrt_allocations\": %llu, \"lodrt_heap_allocations\": %llu, \"not_drawable\": %u, "
                 "\"coarser_than_selected\": %u, "
                 "\"max_sse_px\": %.4f, \"pfrep_ms\": %.4f, \"pfrep_instances\": %u, \"pfrep_triangles\": %llu, "
                 "\"pfrep_changes\": %llu, \"level_histogram\": [",
                 r.frame, r.eye[0], r.eye[1], r.eye[2], r.frame_ms, r.cpu_ms, r.gpu_ms, s.cull_ms, s.select_ms,
                 s.stream_ms, s.upload_ms, s.decode_ms, s.levels_decoded,
                 static_cast<unsigned long long>(s.decode_growths), s.wait_ms, s.visible, s.culled, s.instances_drawn, s.draw_calls,
                 s.textured_draw_calls, static_cast<unsigned long long>(s.triangles), s.levels_resident,
                 static_cast<unsigned long long>(s.resident_bytes), static_cast<unsigned long long>(s.bytes_streamed),
                 s.stream_requests, static_cast<unsigned long long>(s.lodrt_allocations),
                 static_cast<unsigned long long>(s.lodrt_heap_allocations), s.not_drawable, s.coarser_than_selected,
                 double(s.max_sse_px), s.pfrep_ms, s.pfrep_instances,
                 static_cast<unsigned long long>(s.pfrep_triangles), static_cast<unsigned long long>(s.pfrep_changes));
    for (uint32_t l = 0; l < lodrt::kMaxLevels; ++l) std::fprintf(out, "%s%u", l ? ", " : "", s.histogram[l]);
    std::fprintf(out, "]}%s\n", last ? "" : ",");
}

struct Summary {
    double mean_frame_ms = 0, mean_cpu_ms = 0, mean_gpu_ms = 0, mean_triangles = 0, mean_draw_calls = 0;
    double decode_ms = 0; // total over the frames
    uint64_t levels_decoded = 0, decode_growths = 0;
    float max_sse_px = 0;
    uint64_t bytes_streamed = 0, allocations_beyond_requests = 0, heap_allocations = 0;
    uint32_t coarser_frames = 0;
};

Summary summarize(const std::vector<FrameRecord>& records) {
    Summary s;
    for (const FrameRecord& r : records) {
        s.mean_frame_ms += r.frame_ms;
        s.mean_cpu_ms += r.cpu_ms;
        s.mean_gpu_ms += r.gpu_ms;
        s.mean_triangles += double(r.stats.triangles);
        s.mean_draw_calls += r.stats.draw_calls;
        s.max_sse_px = std::max(s.max_sse_px, r.stats.max_sse_px);
        s.bytes_streamed += r.stats.bytes_streamed;
        const uint64_t expected = uint64_t(r.stats.stream_requests) + r.stats.pfrep_decodes;
        if (r.stats.lodrt_allocations > expected) s.allocations_beyond_requests += r.stats.lodrt_allocations - expected;
        s.heap_allocations += r.stats.lodrt_heap_allocations;
        s.decode_ms += r.stats.decode_ms;
        s.levels_decoded += r.stats.levels_decoded;
        s.decode_growths += r.stats.decode_growths;
        if (r.stats.coarser_than_selected || r.stats.not_drawable) ++s.coarser_frames;
    }
    const double n = records.empty() ? 1.0 : double(records.size());
    s.mean_frame_ms /= n;
    s.mean_cpu_ms /= n;
    s.mean_gpu_ms /= n;
    s.mean_triangles /= n;
    s.mean_draw_calls /= n;
    return s;
}

bool writeReport(const Args& args, const lodview::View& view, const std::vector<FrameRecord>& records, const Summary& s,
                 const char* renderer_name) {
    std::FILE* out = std::fopen(args.report.c_str(), "w");
    if (!out) {
        std::fprintf(stderr, "error: %s: cannot write the report\n", args.report.c_str());
        return false;
    }
    std::fprintf(out,
                 "{\n  \"renderer\": \"%s\",\n  \"width\": %u, \"height\": %u, \"mode\": \"%s\", "
                 "\"colour_by_level\": %s, \"instances\": %zu, \"packs\": %zu, \"pixel_threshold\": %g, "
                 "\"budget_bytes\": %llu, \"sync_streaming\": %s,\n  \"frames\": [\n",
                 renderer_name, args.view.width, args.view.height, modeName(args.view.mode),
                 args.view.colour_by_level ? "true" : "false", view.instanceCount(), view.packCount(),
                 double(args.view.pixel_threshold), static_cast<unsigned long long>(args.view.budget_bytes),
                 args.view.sync_streaming ? "true" : "false");
    for (size_t i = 0; i < records.size(); ++i) writeFrameJson(out, records[i], i + 1 == records.size());
    std::fprintf(
        out,
        "  ],\n  \"summary\": {\"frames\": %zu, \"mean_frame_ms\": %.4f, \"mean_cpu_ms\": %.4f, "
        "\"mean_gpu_ms\": %.4f, \"mean_triangles\": %.1f, \"mean_draw_calls\": %.2f, \"max_sse_px\": %.4f, "
        "\"bytes_streamed\": %llu, \"lodrt_allocations_beyond_requests\": %llu, \"lodrt_heap_allocations\": %llu, "
        "\"frames_drawn_coarser\": %u, \"decode_ms\": %.4f, \"levels_decoded\": %llu, \"decode_growths\": %llu}\n}\n",
        records.size(), s.mean_frame_ms, s.mean_cpu_ms, s.mean_gpu_ms, s.mean_triangles, s.mean_draw_calls,
        double(s.max_sse_px), static_cast<unsigned long long>(s.bytes_streamed),
        static_cast<unsigned long long>(s.allocations_beyond_requests),
        static_cast<unsigned long long>(s.heap_allocations), s.coarser_frames, s.decode_ms,
        static_cast<unsigned long long>(s.levels_decoded), static_cast<unsigned long long>(s.decode_growths));
    const bool ok = std::fclose(out) == 0;
    if (!ok) std::fprintf(stderr, "error: %s: cannot write the report\n", args.report.c_str());
    return ok;
}

struct App {
    Args args;
    GLFWwindow* window = nullptr;
    lodview::View view;
    lodview::Renderer renderer;
    WriteRgb8 write_png = nullptr;
    // Interactive state.
    bool paused = false;
    int step = 0;
};

// One frame at path position t. Returns false with a message printed on a lodrt or GL error.
bool runFrame(App& app, float t, FrameRecord* record) {
    const lodview::ViewConfig& config = app.view.config();
    float eye[3], target[3], view[16], proj[16], view_proj[16];
    app.view.camera(t, eye, target);
    lodrt_sample::lookAt(eye, target, view);
    perspectiveGl(config.vertical_fov, float(config.width) / float(config.height), 0.05f, 500.0f, proj);
    lodrt_sample::mul4(proj, view, view_proj);
    std::copy(eye, eye + 3, record->eye);

    const Clock::time_point t0 = Clock::now();
    std::string error;
    if (!app.view.update(eye, view_proj, &app.renderer, &record->stats, &error)) {
        std::fprintf(stderr, "error: %s\n", error.c_str());
        return false;
    }
    app.renderer.beginFrame(view_proj);
    app.view.draw(&app.renderer, &record->stats);
    int ww = 0, wh = 0;
    if (!app.args.headless) glfwGetFramebufferSize(app.window, &ww, &wh);
    app.renderer.endFrame(!app.args.headless, uint32_t(ww), uint32_t(wh));
    const double wait = record->stats.wait_ms;
    record->cpu_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count() - wait;
    glFinish();
    record->frame_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count() - wait;
    record->gpu_ms = app.renderer.gpuMilliseconds();
    if (const GLenum e = glGetError(); e != GL_NO_ERROR) {
        std::fprintf(stderr, "error: OpenGL error 0x%x during the frame\n", unsigned(e));
        return false;
    }
    return true;
}

bool screenshot(App& app, int frame) {
    std::vector<uint8_t> rgb;
    app.renderer.readPixels(&rgb);
    char path[4096];
    std::snprintf(path, sizeof(path), "%s_%04d.png", app.args.screenshot.c_str(), frame);
    char message[512] = {};
    if (app.write_png(path, rgb.data(), app.renderer.width(), app.renderer.height(), message, sizeof(message)) != 0) {
        std::fprintf(stderr, "error: %s: %s\n", path, message);
        return false;
    }
    std::printf("wrote %s\n", path);
    return true;
}

int runHeadless(App& app) {
    const Args& args = app.args;
    FrameRecord scratch;
    for (int w = 0; w < args.warmup; ++w) {
        scratch = FrameRecord();
        if (!runFrame(app, 0.0f, &scratch)) return 1;
    }
    std::vector<FrameRecord> records(size_t(args.frames));
    for (int f = 0; f < args.frames; ++f) {
        records[size_t(f)].frame = f;
        const float t = args.frames > 1 ? float(f) / float(args.frames - 1) : 0.0f;
        if (!runFrame(app, t, &records[size_t(f)])) return 1;
        const bool shot = args.shots.empty() ? f == args.frames - 1
                                             : std::find(args.shots.begin(), args.shots.end(), f) != args.shots.end();
        if (!args.screenshot.empty() && shot && !screenshot(app, f)) return 1;
    }
    const Summary s = summarize(records);
    const char* gl_renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    if (!args.report.empty() && !writeReport(args, app.view, records, s, gl_renderer ? gl_renderer : "?")) return 1;
    std::printf("lodview: %s, %ux%u, %zu instances of %zu packs, mode %s: %d frames, mean frame %.3f ms (cpu %.3f, "
                "gpu %.3f), mean %.0f triangles and %.1f draw calls per frame, max drawn screen-space error %.3f px, "
                "streamed %llu bytes, %llu heap allocations in lodrt\n",
                gl_renderer ? gl_renderer : "?", args.view.width, args.view.height, app.view.instanceCount(),
                app.view.packCount(), modeName(args.view.mode), args.frames, s.mean_frame_ms, s.mean_cpu_ms,
                s.mean_gpu_ms, s.mean_triangles, s.mean_draw_calls, double(s.max_sse_px),
                static_cast<unsigned long long>(s.bytes_streamed), static_cast<unsigned long long>(s.heap_allocations));
    int failed = 0;
    if (args.max_sse > 0 && s.max_sse_px > args.max_sse * 1.0001f) {
        std::fprintf(stderr, "error: a drawn level projects to %.3f px, above --max-sse %.3g px\n",
                     double(s.max_sse_px), double(args.max_sse));
        ++failed;
    }
    return failed ? 1 : 0;
}

void onKey(GLFWwindow* window, int key, int, int action, int) {
    if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
    App& app = *static_cast<App*>(glfwGetWindowUserPointer(window));
    const lodview::ViewConfig& c = app.view.config();
    if (key == GLFW_KEY_ESCAPE) glfwSetWindowShouldClose(window, 1);
    if (key == GLFW_KEY_L)
        app.view.setMode(c.mode == lodview::LodMode::Lod ? lodview::LodMode::ForceLod0 : lodview::LodMode::Lod);
    if (key == GLFW_KEY_P)
        app.view.setMode(c.mode == lodview::LodMode::Pfrep ? lodview::LodMode::Lod : lodview::LodMode::Pfrep);
    if (key == GLFW_KEY_C) app.view.setColourByLevel(!c.colour_by_level);
    if (key == GLFW_KEY_SPACE) app.paused = !app.paused;
    if (key == GLFW_KEY_RIGHT) app.step += 1;
    if (key == GLFW_KEY_LEFT) app.step -= 1;
}

int runInteractive(App& app) {
    glfwSetWindowUserPointer(app.window, &app);
    glfwSetKeyCallback(app.window, onKey);
    int frame = 0;
    while (!glfwWindowShouldClose(app.window)) {
        FrameRecord record;
        if (!app.paused) ++frame;
        frame += app.step;
        app.step = 0;
        const int n = std::max(app.args.frames, 2);
        frame = ((frame % n) + n) % n;
        if (!runFrame(app, float(frame) / float(n - 1), &record)) return 1;
        char title[256];
        std::snprintf(title, sizeof(title), "lodview  %s%s  frame %.2f ms  %llu tris  %u draws  max SSE %.2f px",
                      modeName(app.view.config().mode), app.view.config().colour_by_level ? " (by level)" : "",
                      record.frame_ms, static_cast<unsigned long long>(record.stats.triangles), record.stats.draw_calls,
                      double(record.stats.max_sse_px));
        glfwSetWindowTitle(app.window, title);
        glfwSwapBuffers(app.window);
        glfwPollEvents();
    }
    return 0;
}

int runApp(App& app) {
    std::string error;
    if (!app.view.open(app.args.packs, &error) || !app.view.init(app.args.view, &error)) {
        std::fprintf(stderr, "error: %s\n", error.c_str());
        return 1;
    }
    if (!app.args.screenshot.empty() && !(app.write_png = loadImageWriter(&error))) {
        std::fprintf(stderr, "error: %s\n", error.c_str());
        return 1;
    }
    if (!app.renderer.init(app.args.view.width, app.args.view.height, &error)) {
        std::fprintf(stderr, "error: OpenGL: %s\n", error.c_str());
        return 1;
    }
    const int code = app.args.headless ? runHeadless(app) : runInteractive(app);
    app.view.drain();
    app.view.releaseGpu(&app.renderer);
    return code;
}

} // namespace

int main(int argc, char** argv) {
    Args args;
    if (!parseArgs(argc, argv, &args)) return 2;
    if (!glfwInit()) {
        std::fprintf(stderr, "error: GLFW: cannot initialise (no display? run under xvfb-run for --headless)\n");
        return 1;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, args.headless ? GLFW_FALSE : GLFW_TRUE);
    // Headless runs draw into the renderer's framebuffer; the window only carries the context.
    const int w = args.headless ? 64 : int(args.view.width), h = args.headless ? 64 : int(args.view.height);
    GLFWwindow* window = glfwCreateWindow(w, h, "lodview", nullptr, nullptr);
    if (!window) {
        std::fprintf(stderr, "error: GLFW: cannot create an OpenGL 3.3 core window\n");
        glfwTerminate();
        return 1;
    }
    glfwMakeContextCurrent(window);
    glfwSwapInterval(args.headless ? 0 : 1);
    int code = 0;
    {
        // GL objects are released while the context still exists.
        App app;
        app.args = args;
        app.window = window;
        code = runApp(app);
    }
#ifdef LODVIEW_LEAK_CHECK
    // Everything of lodview and lodrt is freed now. Check here, while the GL driver is still
    // loaded: at exit Mesa has unloaded it, and what it keeps for the process lifetime could no
    // longer be told apart from a leak of ours (tests/runtime/lodview_lsan.supp names it).
    __lsan_do_leak_check();
#endif
    glfwDestroyWindow(window);
    glfwTerminate();
    return code;
}
