#include "lodbake/io/mesh_io.h"

#include "lodbake/core/file_io.h"
#include "lodbake/io/gltf.h"
#include "lodbake/io/conf.h"
#include "lodbake/io/obj.h"
#include "lodbake/io/off.h"
#include "lodbake/io/ply.h"

#include <filesystem>

namespace lodbake {

MeshFormat formatFromPath(const std::string& path) {
    const std::string ext = lowerExtension(path);
    if (ext == ".ply") return MeshFormat::Ply;
    if (ext == ".obj") return MeshFormat::Obj;
    if (ext == ".off") return MeshFormat::Off;
    if (ext == ".gltf") return MeshFormat::Gltf;
    if (ext == ".glb") return MeshFormat::Glb;
    if (ext == ".conf") return MeshFormat::Conf;
    return MeshFormat::Unknown;
}

const char* formatName(MeshFormat format) {
    switch (format) {
    case MeshFormat::Ply: return "PLY";
    case MeshFormat::Obj: return "OBJ";
    case MeshFormat::Off: return "OFF";
    case MeshFormat::Gltf: return "glTF";
    case MeshFormat::Glb: return "GLB";
    case MeshFormat::Conf: return "Stanford .conf";
    case MeshFormat::Unknown: break;
    }
    return "unknown";
}

namespace {

// Side files are named relative to the file that references them; record each one read.
SideFileLoader fileLoader(SourceInfo& source) {
    return [&source](const std::string& path) -> Result<std::vector<uint8_t>> {
        source.files_read.push_back(path);
        return readFileBytes(path);
    };
}

} // namespace

Result<LoadedMesh> readMesh(const std::string& path, const ReadOptions& options, Diagnostics& diagnostics) {
    const MeshFormat format = formatFromPath(path);
    if (format == MeshFormat::Unknown)
        return unsupported(path + ": unknown file extension \"" + lowerExtension(path) +
                           "\", expected .ply, .obj, .off, .gltf, .glb or .conf");
    if (format == MeshFormat::Conf) {
        Result<LoadedMesh> conf = readConf(path, options, diagnostics);
        if (conf.ok()) LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(conf->mesh, path));
        return conf;
    }
    LODBAKE_ASSIGN_OR_RETURN(FileBytes bytes, readLargeFile(path));
    SourceInfo side;
    Result<LoadedMesh> result = [&]() -> Result<LoadedMesh> {
        switch (format) {
        case MeshFormat::Ply: return readPlyFromMemory(bytes.data(), bytes.size(), path, options, diagnostics);
        case MeshFormat::Off: return readOffFromMemory(bytes.data(), bytes.size(), path, options, diagnostics);
        case MeshFormat::Obj:
            return readObjFromMemory(bytes.data(), bytes.size(), path, fileLoader(side), options, diagnostics);
        case MeshFormat::Gltf:
        case MeshFormat::Glb:
            return readGltfFromMemory(bytes.data(), bytes.size(), path, fileLoader(side), options, diagnostics);
        case MeshFormat::Conf:
        case MeshFormat::Unknown: break;
        }
        return internalError(path + ": no reader");
    }();
    if (!result.ok()) return result;
    LoadedMesh loaded = std::move(result).value();
    loaded.source.format = format;
    loaded.source.files_read.clear();
    loaded.source.files_read.push_back(path);
    for (const std::string& f : side.files_read) loaded.source.files_read.push_back(f);
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(loaded.mesh, path));
    return loaded;
}

Result<LoadedScene> readMeshScene(const std::string& path, const ReadOptions& options, Diagnostics& diagnostics) {
    const MeshFormat format = formatFromPath(path);
    LoadedScene scene;
    if (format != MeshFormat::Gltf && format != MeshFormat::Glb) {
        LODBAKE_ASSIGN_OR_RETURN(scene.flat, readMesh(path, options, diagnostics));
        return scene;
    }
    LODBAKE_ASSIGN_OR_RETURN(FileBytes bytes, readLargeFile(path));
    SourceInfo side;
    LODBAKE_ASSIGN_OR_RETURN(scene,
                             readGltfSceneFromMemory(bytes.data(), bytes.size(), path, fileLoader(side), options,
                                                     diagnostics));
    SourceInfo& source = scene.isGraph() ? scene.source : scene.flat.source;
    source.format = format;
    source.files_read.clear();
    source.files_read.push_back(path);
    for (const std::string& f : side.files_read) source.files_read.push_back(f);
    if (!scene.isGraph()) LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(scene.flat.mesh, path));
    return scene;
}

Status writeMesh(const Mesh& mesh, const std::string& path, const WriteOptions& options, Diagnostics& diagnostics) {
    (void)diagnostics;
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, path));
    const MeshFormat format = formatFromPath(path);
    AtomicFileWriter out;
    switch (format) {
    case MeshFormat::Ply: {
        LODBAKE_RETURN_IF_ERROR(out.add(path, writePlyToMemory(mesh, options.ply_binary)));
        break;
    }
    case MeshFormat::Off: {
        LODBAKE_RETURN_IF_ERROR(out.add(path, writeOffToMemory(mesh)));
        break;
    }
    case MeshFormat::Obj: {
        const std::string dir = parentDirectory(path);
        const std::string stem = std::filesystem::path(path).stem().string();
        ObjFiles files = writeObjToMemory(mesh, stem);
        LODBAKE_RETURN_IF_ERROR(out.add(path, files.obj_text));
        if (!files.mtl_text.empty()) LODBAKE_RETURN_IF_ERROR(out.add(joinPath(dir, files.mtl_name), files.mtl_text));
        for (const auto& tex : files.textures) LODBAKE_RETURN_IF_ERROR(out.add(joinPath(dir, tex.first), tex.second));
        break;
    }
    case MeshFormat::Gltf:
    case MeshFormat::Glb: {
        GltfWriteOptions gopt;
        gopt.binary = format == MeshFormat::Glb;
        gopt.bin_name = std::filesystem::path(path).stem().string() + ".bin";
        LODBAKE_ASSIGN_OR_RETURN(GltfFiles files, writeGltfToMemory(mesh, gopt));
        LODBAKE_RETURN_IF_ERROR(out.add(path, files.main));
        if (!gopt.binary) LODBAKE_RETURN_IF_ERROR(out.add(joinPath(parentDirectory(path), gopt.bin_name), files.bin));
        break;
    }
    case MeshFormat::Conf:
    case MeshFormat::Unknown:
        return unsupported(path + ": unknown output extension \"" + lowerExtension(path) +
                           "\", expected .ply, .obj, .off, .gltf or .glb");
    }
    return out.commit();
}

} // namespace lodbake
