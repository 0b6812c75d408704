// liblodbake_open3d: every Open3D call of the baker (loaded on demand, see open3d_module.h).
#include "reconstruct/open3d_module.h"

#include <exception>
#include <memory>
#include <tuple>

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/utility/Logging.h>

namespace {

bool runPoisson(const lodbake::open3d_module::PoissonInput* in, lodbake::open3d_module::PoissonOutput* out,
                std::string* error) {
    try {
        // Library code never prints: Open3D's info and warning lines are silenced; its errors arrive
        // as exceptions, caught below.
        open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
        open3d::geometry::PointCloud cloud;
        cloud.points_.resize(in->point_count);
        cloud.normals_.resize(in->point_count);
        for (size_t i = 0; i < in->point_count; ++i) {
            cloud.points_[i] = Eigen::Vector3d(in->positions[3 * i], in->positions[3 * i + 1], in->positions[3 * i + 2]);
            cloud.normals_[i] = Eigen::Vector3d(in->normals[3 * i], in->normals[3 * i + 1], in->normals[3 * i + 2]);
        }
        std::shared_ptr<open3d::geometry::TriangleMesh> mesh;
        std::vector<double> density;
        std::tie(mesh, density) = open3d::geometry::TriangleMesh::CreateFromPointCloudPoisson(
            cloud, size_t(in->depth), 0.0f, in->scale, false, in->threads);
        if (!mesh || density.size() != mesh->vertices_.size()) {
            *error = "the Poisson reconstruction returned no surface";
            return false;
        }
        out->positions.resize(mesh->vertices_.size() * 3);
        for (size_t v = 0; v < mesh->vertices_.size(); ++v)
            for (int k = 0; k < 3; ++k) out->positions[3 * v + size_t(k)] = float(mesh->vertices_[v][k]);
        out->indices.resize(mesh->triangles_.size() * 3);
        for (size_t f = 0; f < mesh->triangles_.size(); ++f)
            for (int k = 0; k < 3; ++k) out->indices[3 * f + size_t(k)] = uint32_t(mesh->triangles_[f][k]);
        out->density = std::move(density);
        return true;
    } catch (const std::bad_alloc&) {
        *error = "out of memory in the Poisson reconstruction";
    } catch (const std::exception& e) {
        *error = std::string("the Poisson reconstruction failed: ") + e.what();
    } catch (...) {
        *error = "the Poisson reconstruction failed";
    }
    return false;
}

const lodbake::open3d_module::Api kApi{lodbake::open3d_module::kApiVersion, &runPoisson};

} // namespace

extern "C" __attribute__((visibility("default"))) const lodbake::open3d_module::Api* lodbake_open3d_api() {
    return &kApi;
}
