#include <corocontact/contact/winding_number.hpp>

#include <cmath>

namespace coro {

double winding_number(CRef<Positions> vertices, const Tris& faces, const Vec3& point)
{
    // Van Oosterom & Strackee (1983): tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (b·c)|a| + (c·a)|b|).
    double sum = 0.0;
    for (Index f = 0; f < faces.rows(); ++f) {
        const Vec3 a = vertices.row(faces(f, 0)).transpose() - point;
        const Vec3 b = vertices.row(faces(f, 1)).transpose() - point;
        const Vec3 c = vertices.row(faces(f, 2)).transpose() - point;
        const double la = a.norm(), lb = b.norm(), lc = c.norm();
        const double numerator = a.dot(b.cross(c));
        const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
        sum += 2.0 * std::atan2(numerator, denominator);
    }
    return sum / (4.0 * M_PI);
}

} // namespace coro
