#include <corocontact/contact/aabb.hpp>

namespace coro {

Aabb bounding_box(CRef<Positions> vertices)
{
    Aabb box;
    for (Eigen::Index i = 0; i < vertices.rows(); ++i)
        box.extend(Vec3(vertices.row(i).transpose()));
    return box;
}

} // namespace coro
