#pragma once
// lodview's OpenGL 3.3 core side: one GPU copy per resident pack level (float position and texture
// coordinate buffers and a uint32 index buffer, as LevelDecoder decoded the level),
// a flat-shading program, an offscreen framebuffer of the requested size (so a headless run reads
// back the same pixels an interactive run shows), and GL_TIME_ELAPSED queries for GPU frame time.
// Needs a current context (GLFW creates it); functions come from libepoxy.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "level_decode.h"
#include "lodrt/lodrt.h"

namespace lodview {

/// GPU copy of one level of one model: one draw range per TRIANGLES primitive.
struct GpuLevel {
    struct Range {
        uint32_t vao = 0;
        uint32_t first_index = 0; // into the level's index buffer
        uint32_t index_count = 0;
        uint32_t texture = 0; // base colour texture, 0 when the material has none (or no decoder)
    };
    std::vector<uint32_t> buffers;  // vertex buffers (per primitive: positions, texture coordinates) and indices
    std::vector<uint32_t> textures; // base colour textures of its materials
    std::vector<Range> ranges;
    uint64_t triangles = 0;
    bool valid = false;
};

class Renderer {
public:
    Renderer() = default;
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Compiles the program and creates the framebuffer. False with *error set on failure.
    bool init(uint32_t width, uint32_t height, std::string* error);

    /// Uploads a level as `level` decoded it: per primitive a float position buffer and, where its
    /// material has a base colour texture (an image in a buffer view, read with
    /// PackSource::readBufferView and decoded with stb_image) and the texture coordinates it names,
    /// a float texture coordinate buffer and that texture; one uint32 index buffer for the level.
    /// False with *error set when the level has no TRIANGLES primitive.
    bool upload(const lodrt::PackSource& source, const LevelDecoder& level, GpuLevel* out, std::string* error);
    void release(GpuLevel* level);

    /// PFRep instances: one float3 position buffer per model (re-specified in place when more
    /// of the prefix arrives, so vertex arrays that use it stay valid) and per instance a vertex
    /// array with its own index buffer, rewritten when the instance's mask changes.
    void uploadPositions(const float* xyz, size_t vertex_count, uint32_t* vbo);
    void createDynamicMesh(uint32_t vbo, uint32_t* vao, uint32_t* ibo);
    void uploadIndices(uint32_t ibo, const uint32_t* indices, size_t count);
    uint32_t drawDynamic(uint32_t vao, size_t index_count, const float model[16], const float colour[3]);
    void releaseDynamic(uint32_t* vao, uint32_t* ibo);
    void releaseBuffer(uint32_t* vbo);

    /// Frame: binds the framebuffer, clears, starts the GPU timer.
    void beginFrame(const float view_proj[16]);
    /// One draw call per range, textured where the range has a texture and `textured`; returns the
    /// draw calls made and adds the textured ones to *textured_calls.
    uint32_t draw(const GpuLevel& level, const float model[16], const float colour[3], bool textured,
                  uint32_t* textured_calls);
    /// Ends the GPU timer; copies the framebuffer to the window's when `to_window`.
    void endFrame(bool to_window, uint32_t window_width, uint32_t window_height);
    /// GPU time of the last frame in milliseconds (waits for the query), or -1 when timer queries
    /// are unsupported.
    double gpuMilliseconds();
    /// Reads the framebuffer as 8-bit RGB, rows top to bottom.
    void readPixels(std::vector<uint8_t>* rgb);

    uint32_t width() const { return width_; }
    uint32_t height() const { return height_; }

private:
    uint32_t program_ = 0, fbo_ = 0, colour_rb_ = 0, depth_rb_ = 0, query_ = 0;
    int u_view_proj_ = -1, u_model_ = -1, u_colour_ = -1, u_textured_ = -1, u_texture_ = -1;
    uint32_t width_ = 0, height_ = 0;
    bool query_pending_ = false;
};

} // namespace lodview
