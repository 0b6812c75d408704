#include "gl_renderer.h"

#include <epoxy/gl.h>

#include <cstring>

#ifdef LODVIEW_HAS_STB
#include <stb_image.h>
#endif

namespace lodview {

namespace {

// Flat shading from screen-space derivatives of the world position, so levels need no normals
// (a coarse level's faceting is what the viewer is meant to show) and both sides are lit alike.
constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec2 a_uv;
uniform mat4 u_view_proj;
uniform mat4 u_model;
out vec3 v_world;
out vec2 v_uv;
void main() {
    vec4 world = u_model * vec4(a_position, 1.0);
    v_world = world.xyz;
    v_uv = a_uv;
    gl_Position = u_view_proj * world;
}
)";

constexpr const char* kFragmentShader = R"(#version 330 core
in vec3 v_world;
in vec2 v_uv;
uniform vec3 u_colour;
uniform int u_textured;
uniform sampler2D u_texture;
out vec4 o_colour;
void main() {
    vec3 n = normalize(cross(dFdx(v_world), dFdy(v_world)));
    vec3 light = normalize(vec3(0.4, 0.8, 0.45));
    float lit = 0.25 + 0.75 * abs(dot(n, light));
    vec3 base = u_textured != 0 ? texture(u_texture, v_uv).rgb : u_colour;
    o_colour = vec4(base * lit, 1.0);
}
)";

bool compile(GLenum kind, const char* text, GLuint* out, std::string* error) {
    const GLuint shader = glCreateShader(kind);
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = {};
        glGetShaderInfoLog(shader, sizeof(log), nullptr, log);
        *error = std::string("shader compile: ") + log;
        glDeleteShader(shader);
        return false;
    }
    *out = shader;
    return true;
}

// Reads and decodes an image buffer view into a mipmapped RGBA8 texture; 0 when it cannot.
uint32_t loadTexture(const lodrt::PackSource& source, uint32_t view) {
#ifdef LODVIEW_HAS_STB
    const uint64_t size = source.pack().bufferView(view).byte_length;
    if (size == 0 || size > (uint64_t(1) << 30)) return 0;
    std::vector<uint8_t> bytes(size);
    if (source.readBufferView(view, 0, bytes.data(), bytes.size()) != lodrt::Result::Ok) return 0;
    int w = 0, h = 0, n = 0;
    uint8_t* rgba = stbi_load_from_memory(bytes.data(), int(bytes.size()), &w, &h, &n, 4);
    if (!rgba) return 0;
    GLuint texture = 0;
    glGenTextures(1, &texture);
    glBindTexture(GL_TEXTURE_2D, texture);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    // glTF texture coordinates start at the image's first row, which is what GL samples at t = 0.
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glBindTexture(GL_TEXTURE_2D, 0);
    stbi_image_free(rgba);
    return texture;
#else
    (void)source;
    (void)view;
    return 0;
#endif
}

// Uploads `count` elements of `components` floats as vertex attribute `location` of the bound
// vertex array.
void uploadFloats(const float* data, size_t count, GLuint location, GLint components, GpuLevel* out) {
    GLuint vbo = 0;
    glGenBuffers(1, &vbo);
    out->buffers.push_back(vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(count * size_t(components) * sizeof(float)), data, GL_STATIC_DRAW);
    glEnableVertexAttribArray(location);
    glVertexAttribPointer(location, components, GL_FLOAT, GL_FALSE, 0, nullptr);
}

} // namespace

Renderer::~Renderer() {
    if (program_) glDeleteProgram(program_);
    if (fbo_) glDeleteFramebuffers(1, &fbo_);
    if (colour_rb_) glDeleteRenderbuffers(1, &colour_rb_);
    if (depth_rb_) glDeleteRenderbuffers(1, &depth_rb_);
    if (query_) glDeleteQueries(1, &query_);
}

bool Renderer::init(uint32_t width, uint32_t height, std::string* error) {
    width_ = width;
    height_ = height;
    GLuint vs = 0, fs = 0;
    if (!compile(GL_VERTEX_SHADER, kVertexShader, &vs, error)) return false;
    if (!compile(GL_FRAGMENT_SHADER, kFragmentShader, &fs, error)) {
        glDeleteShader(vs);
        return false;
    }
    program_ = glCreateProgram();
    glAttachShader(program_, vs);
    glAttachShader(program_, fs);
    glLinkProgram(program_);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(program_, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024] = {};
        glGetProgramInfoLog(program_, sizeof(log), nullptr, log);
        *error = std::string("program link: ") + log;
        return false;
    }
    u_view_proj_ = glGetUniformLocation(program_, "u_view_proj");
    u_model_ = glGetUniformLocation(program_, "u_model");
    u_colour_ = glGetUniformLocation(program_, "u_colour");
    u_textured_ = glGetUniformLocation(program_, "u_textured");
    u_texture_ = glGetUniformLocation(program_, "u_texture");
    glUseProgram(program_);
    glUniform1i(u_texture_, 0);
    glUseProgram(0);

    glGenRenderbuffers(1, &colour_rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, colour_rb_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, GLsizei(width), GLsizei(height));
    glGenRenderbuffers(1, &depth_rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_rb_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, GLsizei(width), GLsizei(height));
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour_rb_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        *error = "the offscreen framebuffer is incomplete";
        return false;
    }
    if (epoxy_gl_version() >= 33 || epoxy_has_gl_extension("GL_ARB_timer_query")) glGenQueries(1, &query_);
    return true;
}

bool Renderer::upload(const lodrt::PackSource& source, const LevelDecoder& level, GpuLevel* out, std::string* error) {
    if (level.primitives().empty()) {
        *error = "the level has no TRIANGLES primitive";
        return false;
    }
    GLuint ibo = 0;
    glGenBuffers(1, &ibo);
    out->buffers.push_back(ibo);
    for (const DecodedPrimitive& prim : level.primitives()) {
        GLuint vao = 0;
        glGenVertexArrays(1, &vao);
        glBindVertexArray(vao);
        out->ranges.push_back({vao, prim.first_index, prim.index_count, 0});
        uploadFloats(level.positions() + 3 * size_t(prim.first_vertex), prim.vertex_count, 0, 3, out);
        if (prim.image_view != lodrt::kNoIndex && prim.has_uv) {
            uploadFloats(level.uvs() + 2 * size_t(prim.first_vertex), prim.vertex_count, 1, 2, out);
            out->ranges.back().texture = loadTexture(source, prim.image_view);
            if (out->ranges.back().texture) out->textures.push_back(out->ranges.back().texture);
        }
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
        glBindVertexArray(0);
        out->triangles += prim.index_count / 3;
    }
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(size_t(level.indexCount()) * sizeof(uint32_t)), level.indices(),
                 GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    out->valid = true;
    return true;
}

void Renderer::release(GpuLevel* level) {
    for (const GpuLevel::Range& r : level->ranges) glDeleteVertexArrays(1, &r.vao);
    if (!level->textures.empty()) glDeleteTextures(GLsizei(level->textures.size()), level->textures.data());
    if (!level->buffers.empty()) glDeleteBuffers(GLsizei(level->buffers.size()), level->buffers.data());
    *level = GpuLevel();
}

void Renderer::uploadPositions(const float* xyz, size_t vertex_count, uint32_t* vbo) {
    if (!*vbo) glGenBuffers(1, vbo);
    glBindBuffer(GL_ARRAY_BUFFER, *vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertex_count * 3 * sizeof(float)), xyz, GL_STATIC_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void Renderer::createDynamicMesh(uint32_t vbo, uint32_t* vao, uint32_t* ibo) {
    glGenVertexArrays(1, vao);
    glBindVertexArray(*vao);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glGenBuffers(1, ibo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, *ibo);
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void Renderer::uploadIndices(uint32_t ibo, const uint32_t* indices, size_t count) {
    glBindVertexArray(0);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(count * sizeof(uint32_t)), indices, GL_DYNAMIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
}

uint32_t Renderer::drawDynamic(uint32_t vao, size_t index_count, const float model[16], const float colour[3]) {
    glUniform1i(u_textured_, 0);
    glUniformMatrix4fv(u_model_, 1, GL_FALSE, model);
    glUniform3fv(u_colour_, 1, colour);
    glBindVertexArray(vao);
    glDrawElements(GL_TRIANGLES, GLsizei(index_count), GL_UNSIGNED_INT, nullptr);
    return 1;
}

void Renderer::releaseDynamic(uint32_t* vao, uint32_t* ibo) {
    if (*vao) glDeleteVertexArrays(1, vao);
    if (*ibo) glDeleteBuffers(1, ibo);
    *vao = *ibo = 0;
}

void Renderer::releaseBuffer(uint32_t* vbo) {
    if (*vbo) glDeleteBuffers(1, vbo);
    *vbo = 0;
}

void Renderer::beginFrame(const float view_proj[16]) {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, GLsizei(width_), GLsizei(height_));
    if (query_) {
        glBeginQuery(GL_TIME_ELAPSED, query_);
        query_pending_ = true;
    }
    glEnable(GL_DEPTH_TEST);
    glClearColor(0.62f, 0.70f, 0.78f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glUseProgram(program_);
    glUniformMatrix4fv(u_view_proj_, 1, GL_FALSE, view_proj);
}

uint32_t Renderer::draw(const GpuLevel& level, const float model[16], const float colour[3], bool textured,
                        uint32_t* textured_calls) {
    glUniformMatrix4fv(u_model_, 1, GL_FALSE, model);
    glUniform3fv(u_colour_, 1, colour);
    for (const GpuLevel::Range& r : level.ranges) {
        const bool use = textured && r.texture != 0;
        glUniform1i(u_textured_, use ? 1 : 0);
        if (use) {
            glActiveTexture(GL_TEXTURE0);
            glBindTexture(GL_TEXTURE_2D, r.texture);
            ++*textured_calls;
        }
        glBindVertexArray(r.vao);
        glDrawElements(GL_TRIANGLES, GLsizei(r.index_count), GL_UNSIGNED_INT,
                       reinterpret_cast<const void*>(uintptr_t(r.first_index) * sizeof(uint32_t)));
    }
    return uint32_t(level.ranges.size());
}

void Renderer::endFrame(bool to_window, uint32_t window_width, uint32_t window_height) {
    glBindVertexArray(0);
    if (query_) glEndQuery(GL_TIME_ELAPSED);
    if (to_window) {
        glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
        glBlitFramebuffer(0, 0, GLint(width_), GLint(height_), 0, 0, GLint(window_width), GLint(window_height),
                          GL_COLOR_BUFFER_BIT, GL_LINEAR);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    }
}

double Renderer::gpuMilliseconds() {
    if (!query_ || !query_pending_) return -1;
    GLuint64 ns = 0;
    glGetQueryObjectui64v(query_, GL_QUERY_RESULT, &ns);
    query_pending_ = false;
    return double(ns) * 1e-6;
}

void Renderer::readPixels(std::vector<uint8_t>* rgb) {
    const size_t row = size_t(width_) * 3;
    std::vector<uint8_t> flipped(row * height_);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, GLsizei(width_), GLsizei(height_), GL_RGB, GL_UNSIGNED_BYTE, flipped.data());
    rgb->resize(flipped.size());
    // GL rows run bottom to top; PNG rows top to bottom.
    for (uint32_t y = 0; y < height_; ++y)
        std::memcpy(rgb->data() + size_t(y) * row, flipped.data() + size_t(height_ - 1 - y) * row, row);
}

} // namespace lodview
