#include "gl_renderer.h"

#include <epoxy/gl.h>

#include <cstring>

namespace lodview {

namespace {

// Flat shading from screen-space derivatives of the world position, so levels need no normals
// (a coarse level's faceting is what the viewer is meant to show) and both sides are lit alike.
constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
uniform mat4 u_view_proj;
uniform mat4 u_model;
out vec3 v_world;
void main() {
    vec4 world = u_model * vec4(a_position, 1.0);
    v_world = world.xyz;
    gl_Position = u_view_proj * world;
}
)";

constexpr const char* kFragmentShader = R"(#version 330 core
in vec3 v_world;
uniform vec3 u_colour;
out vec4 o_colour;
void main() {
    vec3 n = normalize(cross(dFdx(v_world), dFdy(v_world)));
    vec3 light = normalize(vec3(0.4, 0.8, 0.45));
    float lit = 0.25 + 0.75 * abs(dot(n, light));
    o_colour = vec4(u_colour * lit, 1.0);
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

GLenum glComponentType(lodrt::ComponentType type) {
    switch (type) {
    case lodrt::ComponentType::Byte:
        return GL_BYTE;
    case lodrt::ComponentType::UnsignedByte:
        return GL_UNSIGNED_BYTE;
    case lodrt::ComponentType::Short:
        return GL_SHORT;
    case lodrt::ComponentType::UnsignedShort:
        return GL_UNSIGNED_SHORT;
    case lodrt::ComponentType::UnsignedInt:
        return GL_UNSIGNED_INT;
    case lodrt::ComponentType::Float:
        return GL_FLOAT;
    }
    return GL_FLOAT;
}

// The POSITION accessor of primitive p, or kNoIndex.
uint32_t positionAccessor(const lodrt::Pack& pack, const lodrt::PrimitiveInfo& prim) {
    for (uint32_t a = 0; a < prim.attribute_count; ++a) {
        const lodrt::AttributeInfo& attribute = pack.attribute(prim.first_attribute + a);
        if (attribute.name == "POSITION") return attribute.accessor;
    }
    return lodrt::kNoIndex;
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

bool Renderer::upload(const lodrt::PackSource& source, uint32_t model, uint32_t level, const uint8_t* bytes,
                      uint32_t* indices, size_t index_capacity, GpuLevel* out, std::string* error) {
    const lodrt::Pack& pack = source.pack();
    const lodrt::LevelInfo& info = source.models().modelLevel(model, level);
    size_t index_count = 0;
    if (source.copyLevelIndices(model, level, bytes, indices, index_capacity, &index_count) != lodrt::Result::Ok) {
        *error = "cannot widen the level's indices";
        return false;
    }
    const lodrt::MeshInfo& mesh = pack.mesh(info.mesh);
    GLuint ibo = 0;
    glGenBuffers(1, &ibo);
    out->buffers.push_back(ibo);
    uint32_t first = 0;
    for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
        const lodrt::PrimitiveInfo& prim = pack.primitive(mesh.first_primitive + p);
        if (prim.mode != 4) continue;
        const uint32_t count = uint32_t(prim.index_count);
        const uint32_t accessor = positionAccessor(pack, prim);
        const lodrt::AccessorInfo* acc = accessor == lodrt::kNoIndex ? nullptr : &pack.accessor(accessor);
        const uint8_t* data = acc ? source.accessorData(model, level, bytes, accessor) : nullptr;
        if (!acc || !data || acc->type != lodrt::AccessorType::Vec3 || acc->count == 0) {
            *error = "a primitive has no POSITION data inside the level's bytes";
            return false;
        }
        const uint32_t stride = pack.bufferView(acc->buffer_view).byte_stride;
        const uint64_t step = stride ? stride : acc->element_size;
        GLuint vao = 0, vbo = 0;
        glGenVertexArrays(1, &vao);
        glBindVertexArray(vao);
        glGenBuffers(1, &vbo);
        out->buffers.push_back(vbo);
        glBindBuffer(GL_ARRAY_BUFFER, vbo);
        glBufferData(GL_ARRAY_BUFFER, GLsizeiptr((acc->count - 1) * step + acc->element_size), data, GL_STATIC_DRAW);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 3, glComponentType(acc->component_type), acc->normalized ? GL_TRUE : GL_FALSE,
                              GLsizei(stride), nullptr);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
        glBindVertexArray(0);
        out->ranges.push_back({vao, first, count});
        out->triangles += count / 3;
        first += count;
    }
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(index_count * sizeof(uint32_t)), indices, GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    if (first != index_count) {
        *error = "the level's index count does not match its primitives";
        return false;
    }
    out->valid = true;
    return true;
}

void Renderer::release(GpuLevel* level) {
    for (const GpuLevel::Range& r : level->ranges) glDeleteVertexArrays(1, &r.vao);
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

uint32_t Renderer::draw(const GpuLevel& level, const float model[16], const float colour[3]) {
    glUniformMatrix4fv(u_model_, 1, GL_FALSE, model);
    glUniform3fv(u_colour_, 1, colour);
    for (const GpuLevel::Range& r : level.ranges) {
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
