// Every rtc* call of corocontact lives in this file (STYLE.md §7): the device, one scene per
// contact surface, the float vertex upload and the axis rays that gather all their hits.
#include "embree_scene_set.hpp"

#include <corocontact/core/error.hpp>

#include <embree3/rtcore.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <exception>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>

namespace coro::detail {

namespace {

constexpr float FLOAT_EPS = std::numeric_limits<float>::epsilon();
constexpr float FLOAT_INF = std::numeric_limits<float>::infinity();

// Float-noise bands, relative to the magnitude m = scale + lead of the float coordinates and
// distances of one axis ray (scale bounds the scene's coordinates, lead is the distance from
// the ray origin to the query point). A hit within T_BAND·m of the query point means the
// point lies on the surface (ON_SURFACE); hits whose distances to the point differ by less
// than T_BAND·m coincide (an edge or a vertex was hit, possibly reported by both faces); a hit
// closer than EDGE_BAND·m to an edge of its face lies on that edge; a face whose normal has a
// relative axis component below PARALLEL_BAND is parallel to the axis. 64 ulps leave a wide
// margin over the few ulps Embree's float intersection loses.
constexpr float T_BAND = 64.0f * FLOAT_EPS;
constexpr float EDGE_BAND = 64.0f * FLOAT_EPS;
constexpr float PARALLEL_BAND = 64.0f * FLOAT_EPS;

// Embree 3 reports the unnormalised geometric normal of a triangle (v0, v1, v2) as
// Ng = (v1 − v0) × (v2 − v0) (also with RTC_SCENE_FLAG_ROBUST), i.e. along the counter-
// clockwise winding normal, which for our faces points outward. Checked by the unit-cube test
// EmbreeUnitCubeAxis.GeometricNormalFollowsWinding; −1 here would mean "against the winding".
constexpr float NG_ALONG_WINDING = 1.0f;

const char* error_name(RTCError code)
{
    switch (code) {
    case RTC_ERROR_NONE: return "RTC_ERROR_NONE";
    case RTC_ERROR_UNKNOWN: return "RTC_ERROR_UNKNOWN";
    case RTC_ERROR_INVALID_ARGUMENT: return "RTC_ERROR_INVALID_ARGUMENT";
    case RTC_ERROR_INVALID_OPERATION: return "RTC_ERROR_INVALID_OPERATION";
    case RTC_ERROR_OUT_OF_MEMORY: return "RTC_ERROR_OUT_OF_MEMORY";
    case RTC_ERROR_UNSUPPORTED_CPU: return "RTC_ERROR_UNSUPPORTED_CPU";
    case RTC_ERROR_CANCELLED: return "RTC_ERROR_CANCELLED";
    }
    return "unknown RTCError";
}

/// One hit recorded by the intersection filter.
struct Hit {
    float t = 0.0f;
    unsigned prim = 0;
    std::array<float, 3> ng{}; ///< Embree's unnormalised geometric normal
    float u = 0.0f;            ///< hit point = (1−u−v)·v0 + u·v1 + v·v2
    float v = 0.0f;
};

/// The hits of one ray: inline storage for the usual handful, a vector beyond.
class HitList {
public:
    void push(const Hit& hit)
    {
        if (m_size < INLINE_CAPACITY) {
            m_inline[m_size] = hit;
        } else {
            if (m_size == INLINE_CAPACITY)
                m_overflow.assign(m_inline.begin(), m_inline.end());
            m_overflow.push_back(hit);
        }
        ++m_size;
    }
    std::size_t size() const { return m_size; }
    bool empty() const { return m_size == 0; }
    Hit* begin() { return m_size <= INLINE_CAPACITY ? m_inline.data() : m_overflow.data(); }
    Hit* end() { return begin() + m_size; }
    const Hit& operator[](std::size_t i) const
    {
        return m_size <= INLINE_CAPACITY ? m_inline[i] : m_overflow[i];
    }

    /// Sorts by (t, prim) (Embree's tutorials/next_hit) after dropping repeated primitives (a
    /// triangle referenced from several BVH leaves reports the same hit more than once).
    void sort_unique()
    {
        if (m_size < 2)
            return;
        std::sort(begin(), end(), [](const Hit& a, const Hit& b) {
            return a.prim != b.prim ? a.prim < b.prim : a.t < b.t;
        });
        Hit* last = std::unique(begin(), end(), [](const Hit& a, const Hit& b) { return a.prim == b.prim; });
        resize(static_cast<std::size_t>(last - begin()));
        std::sort(begin(), end(), [](const Hit& a, const Hit& b) {
            return a.t != b.t ? a.t < b.t : a.prim < b.prim;
        });
    }

private:
    static constexpr std::size_t INLINE_CAPACITY = 16;

    void resize(std::size_t n)
    {
        if (m_size > INLINE_CAPACITY && n <= INLINE_CAPACITY)
            std::copy(m_overflow.begin(), m_overflow.begin() + static_cast<std::ptrdiff_t>(n), m_inline.begin());
        else if (m_size > INLINE_CAPACITY)
            m_overflow.resize(n);
        m_size = n;
    }

    std::array<Hit, INLINE_CAPACITY> m_inline{};
    std::vector<Hit> m_overflow;
    std::size_t m_size = 0;
};

/// The intersection context handed to rtcIntersect1: Embree passes a pointer to `rtc` back to
/// the filter, which recovers the hit list from it (as tutorials/next_hit does).
struct GatherContext {
    RTCIntersectContext rtc; // first member
    HitList* hits = nullptr;
};
static_assert(std::is_standard_layout_v<GatherContext>, "GatherContext must start with the Embree context");

/// Context filter: records every hit and rejects it, so that traversal goes on to the end of
/// the ray segment.
void gather_filter(const RTCFilterFunctionNArguments* args)
{
    auto* context = reinterpret_cast<GatherContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1)
            continue;
        args->valid[i] = 0;
        Hit hit;
        hit.t = RTCRayN_tfar(args->ray, args->N, i);
        hit.prim = RTCHitN_primID(args->hit, args->N, i);
        hit.ng = {RTCHitN_Ng_x(args->hit, args->N, i), RTCHitN_Ng_y(args->hit, args->N, i),
                  RTCHitN_Ng_z(args->hit, args->N, i)};
        hit.u = RTCHitN_u(args->hit, args->N, i);
        hit.v = RTCHitN_v(args->hit, args->N, i);
        context->hits->push(hit);
    }
}

RTCRayHit axis_ray(const std::array<float, 3>& origin, int axis, float direction, float tfar)
{
    RTCRayHit ray_hit{};
    ray_hit.ray.org_x = origin[0];
    ray_hit.ray.org_y = origin[1];
    ray_hit.ray.org_z = origin[2];
    ray_hit.ray.tnear = 0.0f;
    ray_hit.ray.dir_x = axis == 0 ? direction : 0.0f;
    ray_hit.ray.dir_y = axis == 1 ? direction : 0.0f;
    ray_hit.ray.dir_z = axis == 2 ? direction : 0.0f;
    ray_hit.ray.time = 0.0f;
    ray_hit.ray.tfar = tfar;
    ray_hit.ray.mask = std::numeric_limits<unsigned>::max();
    ray_hit.ray.id = 0;
    ray_hit.ray.flags = 0;
    ray_hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    ray_hit.hit.primID = RTC_INVALID_GEOMETRY_ID;
    ray_hit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return ray_hit;
}

struct SurfaceScene {
    RTCScene scene = nullptr;
    RTCGeometry geometry = nullptr;  ///< null for a surface without faces
    float* vertices = nullptr;       ///< Embree-owned float3 buffer, relative to `origin`
    const unsigned* faces = nullptr; ///< Embree-owned uint3 buffer
    Index num_vertices = 0;
    Index num_faces = 0;
    Vec3 origin = Vec3::Zero();      ///< subtracted before the conversion to float
    float scale = 1.0f;              ///< largest |coordinate| relative to origin (≥ FLT_MIN)

    std::array<float, 3> local(const Vec3& point) const
    {
        const Vec3 p = point - origin;
        return {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
    }
    std::array<float, 3> vertex(unsigned v) const
    {
        const float* x = vertices + 3 * static_cast<std::size_t>(v);
        return {x[0], x[1], x[2]};
    }
};

std::array<float, 3> sub(const std::array<float, 3>& a, const std::array<float, 3>& b)
{
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
std::array<float, 3> cross(const std::array<float, 3>& a, const std::array<float, 3>& b)
{
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
float norm(const std::array<float, 3>& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

/// Distance (in the scene's float coordinates) from a hit point to the nearest edge of its face.
float distance_to_edge(const SurfaceScene& scene, const Hit& hit)
{
    const unsigned* f = scene.faces + 3 * static_cast<std::size_t>(hit.prim);
    const std::array<float, 3> v0 = scene.vertex(f[0]), v1 = scene.vertex(f[1]), v2 = scene.vertex(f[2]);
    const float twice_area = norm(cross(sub(v1, v0), sub(v2, v0)));
    // weight of a vertex · altitude onto the opposite edge = distance to that edge
    const float w0 = 1.0f - hit.u - hit.v;
    const float d0 = w0 * twice_area / norm(sub(v2, v1));
    const float d1 = hit.u * twice_area / norm(sub(v0, v2));
    const float d2 = hit.v * twice_area / norm(sub(v1, v0));
    const float d = std::min({d0, d1, d2});
    return std::isfinite(d) ? d : 0.0f; // a zero-length edge: on an edge
}

struct UploadResult {
    float scale = 0.0f;
    bool finite = true;
};

/// Converts the surface's double positions (minus `origin`) to float into Embree's buffer.
UploadResult upload_vertices(const Positions& positions, const Vec3& origin, float* out)
{
    constexpr Index GRAIN = 4096;
    return tbb::parallel_reduce(
        tbb::blocked_range<Index>(0, static_cast<Index>(positions.rows()), GRAIN), UploadResult{},
        [&](const tbb::blocked_range<Index>& r, UploadResult acc) {
            for (Index v = r.begin(); v < r.end(); ++v)
                for (int d = 0; d < 3; ++d) {
                    const float x = static_cast<float>(positions(v, d) - origin[d]);
                    out[3 * static_cast<std::size_t>(v) + static_cast<std::size_t>(d)] = x;
                    acc.finite = acc.finite && std::isfinite(x);
                    acc.scale = std::max(acc.scale, std::abs(x));
                }
            return acc;
        },
        [](const UploadResult& a, const UploadResult& b) {
            return UploadResult{std::max(a.scale, b.scale), a.finite && b.finite};
        });
}

Vec3 box_centre(const ContactSurface& surface)
{
    const Aabb& box = surface.tree.bounds();
    if (!box.empty() && box.min.allFinite() && box.max.allFinite())
        return 0.5 * (box.min + box.max);
    if (surface.vertices.rows() == 0 || !surface.vertices.allFinite())
        return Vec3::Zero();
    const Vec3 lo = surface.vertices.colwise().minCoeff().transpose();
    const Vec3 hi = surface.vertices.colwise().maxCoeff().transpose();
    return 0.5 * (lo + hi);
}

} // namespace

struct EmbreeSceneSet::Impl {
    RTCDevice device = nullptr;
    EmbreeBuild build = EmbreeBuild::REFIT;
    std::vector<SurfaceScene> scenes;
    std::mutex error_mutex;
    /// Per thread (Embree keeps error codes per thread, and scenes commit in parallel tasks):
    /// the first message since that thread's last check, from the callback.
    std::map<std::thread::id, std::string> error_messages;

    Impl() = default;
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;

    ~Impl()
    {
        for (SurfaceScene& s : scenes) {
            if (s.geometry != nullptr)
                rtcReleaseGeometry(s.geometry);
            if (s.scene != nullptr)
                rtcReleaseScene(s.scene);
        }
        if (device != nullptr)
            rtcReleaseDevice(device);
    }

    /// Error callback: only records the message; check() turns it into an exception.
    static void record_error(void* user, RTCError code, const char* message)
    {
        auto* impl = static_cast<Impl*>(user);
        const std::lock_guard<std::mutex> lock(impl->error_mutex);
        std::string& recorded = impl->error_messages[std::this_thread::get_id()];
        if (recorded.empty())
            recorded = std::string(error_name(code)) + ": " + (message != nullptr ? message : "");
    }

    /// rtcGetDeviceError after an Embree call; throws NumericalError with Embree's text.
    void check(const char* call, const ContactSurface& surface)
    {
        const RTCError code = rtcGetDeviceError(device);
        if (code == RTC_ERROR_NONE)
            return;
        std::string message;
        {
            const std::lock_guard<std::mutex> lock(error_mutex);
            const auto recorded = error_messages.find(std::this_thread::get_id());
            if (recorded != error_messages.end()) {
                message = std::move(recorded->second);
                error_messages.erase(recorded);
            }
        }
        if (message.empty())
            message = error_name(code);
        CORO_THROW(NumericalError, "surface '" << surface.name << "': Embree " << call << " failed: " << message);
    }

    void upload(SurfaceScene& s, const ContactSurface& surface)
    {
        s.origin = box_centre(surface);
        const UploadResult r = upload_vertices(surface.vertices, s.origin, s.vertices);
        CORO_CHECK(r.finite, NumericalError,
                   "surface '" << surface.name << "': a vertex coordinate is not finite in float");
        s.scale = std::max(r.scale, std::numeric_limits<float>::min());
    }

    void add_surface(const ContactSurface& surface)
    {
        SurfaceScene& s = scenes.emplace_back();
        s.num_vertices = static_cast<Index>(surface.vertices.rows());
        s.num_faces = static_cast<Index>(surface.faces.rows());

        s.scene = rtcNewScene(device);
        check("rtcNewScene", surface);
        int flags = RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION;
        if (build != EmbreeBuild::MEDIUM_REBUILD)
            flags |= RTC_SCENE_FLAG_DYNAMIC;
        rtcSetSceneFlags(s.scene, static_cast<RTCSceneFlags>(flags));
        rtcSetSceneBuildQuality(s.scene, build == EmbreeBuild::MEDIUM_REBUILD ? RTC_BUILD_QUALITY_MEDIUM
                                                                              : RTC_BUILD_QUALITY_LOW);
        check("scene setup", surface);

        if (s.num_faces > 0) {
            for (Index f = 0; f < s.num_faces; ++f)
                for (int k = 0; k < 3; ++k)
                    CORO_CHECK(surface.faces(f, k) >= 0 && surface.faces(f, k) < s.num_vertices, InputError,
                               "surface '" << surface.name << "': face " << f << " uses vertex "
                                           << surface.faces(f, k) << ", expected 0.." << s.num_vertices - 1);
            s.geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
            check("rtcNewGeometry", surface);
            rtcSetGeometryBuildQuality(s.geometry, build == EmbreeBuild::REFIT         ? RTC_BUILD_QUALITY_REFIT
                                                   : build == EmbreeBuild::LOW_REBUILD ? RTC_BUILD_QUALITY_LOW
                                                                                       : RTC_BUILD_QUALITY_MEDIUM);
            s.vertices = static_cast<float*>(rtcSetNewGeometryBuffer(s.geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                                     RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                                     static_cast<std::size_t>(s.num_vertices)));
            auto* faces = static_cast<unsigned*>(rtcSetNewGeometryBuffer(s.geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                                         RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                                         static_cast<std::size_t>(s.num_faces)));
            check("rtcSetNewGeometryBuffer", surface);
            CORO_CHECK(s.vertices != nullptr && faces != nullptr, NumericalError,
                       "surface '" << surface.name << "': Embree returned no geometry buffer");
            for (Index f = 0; f < s.num_faces; ++f)
                for (int k = 0; k < 3; ++k)
                    faces[3 * static_cast<std::size_t>(f) + static_cast<std::size_t>(k)] =
                        static_cast<unsigned>(surface.faces(f, k));
            s.faces = faces;
            upload(s, surface);
            rtcCommitGeometry(s.geometry);
            check("rtcCommitGeometry", surface);
            rtcAttachGeometry(s.scene, s.geometry);
            check("rtcAttachGeometry", surface);
        }
        rtcCommitScene(s.scene);
        check("rtcCommitScene", surface);
    }

    void update_surface(SurfaceScene& s, const ContactSurface& surface)
    {
        CORO_CHECK(surface.vertices.rows() == s.num_vertices && surface.faces.rows() == s.num_faces, InputError,
                   "surface '" << surface.name << "': " << surface.vertices.rows() << " vertices and "
                               << surface.faces.rows() << " faces, but its Embree scene was built with "
                               << s.num_vertices << " and " << s.num_faces);
        if (s.geometry == nullptr)
            return;
        upload(s, surface);
        rtcUpdateGeometryBuffer(s.geometry, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(s.geometry);
        check("rtcCommitGeometry", surface);
        rtcCommitScene(s.scene);
        check("rtcCommitScene", surface);
    }

    /// All hits of one axis ray, sorted by (t, prim).
    void gather(const SurfaceScene& s, const std::array<float, 3>& origin, int axis, float direction, float tfar,
                HitList& hits, EmbreeQueryCounts* counts) const
    {
        GatherContext context;
        rtcInitIntersectContext(&context.rtc);
        context.rtc.filter = gather_filter;
        context.hits = &hits;
        RTCRayHit ray_hit = axis_ray(origin, axis, direction, tfar);
        rtcIntersect1(s.scene, &context.rtc, &ray_hit);
        hits.sort_unique();
        if (counts != nullptr) {
            ++counts->rays;
            counts->hits += static_cast<std::int64_t>(hits.size());
        }
    }
};

EmbreeSceneSet::EmbreeSceneSet(const std::vector<ContactSurface>& surfaces, EmbreeBuild build)
    : m_impl(std::make_unique<Impl>())
{
    m_impl->build = build;
    m_impl->device = rtcNewDevice(nullptr);
    if (m_impl->device == nullptr) {
        const RTCError code = rtcGetDeviceError(nullptr);
        CORO_THROW(NumericalError, "Embree rtcNewDevice failed: " << error_name(code));
    }
    rtcSetDeviceErrorFunction(m_impl->device, &Impl::record_error, m_impl.get());
    m_impl->scenes.reserve(surfaces.size());
    for (const ContactSurface& surface : surfaces)
        m_impl->add_surface(surface);
}

EmbreeSceneSet::~EmbreeSceneSet() = default;

Index EmbreeSceneSet::size() const { return static_cast<Index>(m_impl->scenes.size()); }

void EmbreeSceneSet::update(const std::vector<ContactSurface>& surfaces)
{
    CORO_CHECK(surfaces.size() == m_impl->scenes.size(), InputError,
               "Embree scenes: " << surfaces.size() << " surfaces given, " << m_impl->scenes.size()
                                 << " scenes were built");
    // The scenes commit as parallel tasks; of several failures, the first surface's is thrown.
    std::vector<std::exception_ptr> failures(surfaces.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, surfaces.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i < r.end(); ++i) {
                              try {
                                  m_impl->update_surface(m_impl->scenes[i], surfaces[i]);
                              } catch (...) {
                                  failures[i] = std::current_exception();
                              }
                          }
                      });
    for (const std::exception_ptr& failure : failures)
        if (failure)
            std::rethrow_exception(failure);
}

AxisOutcome EmbreeSceneSet::axis_test(Index s, const Vec3& point, int axis, EmbreeQueryCounts* counts) const
{
    return axis_test(s, point, axis, counts, nullptr);
}

AxisOutcome EmbreeSceneSet::axis_test(Index s, const Vec3& point, int axis, EmbreeQueryCounts* counts,
                                      double* distance_bound) const
{
    CORO_ASSERT(s >= 0 && s < size() && axis >= 0 && axis < 3);
    const SurfaceScene& scene = m_impl->scenes[static_cast<std::size_t>(s)];
    if (counts != nullptr)
        ++counts->axis_tests;
    if (scene.num_faces == 0)
        return AxisOutcome::NO_HIT;
    std::array<float, 3> origin = scene.local(point);
    CORO_CHECK(std::isfinite(origin[0]) && std::isfinite(origin[1]) && std::isfinite(origin[2]), NumericalError,
               "Embree axis test: query point (" << point.transpose() << ") is not finite in float");

    // The whole axis line as one ray along +axis that starts below the scene (every vertex has
    // |coordinate| ≤ scale): Embree needs tnear ≥ 0 and does not promise hits at exactly tnear,
    // so a ray starting at the point could miss a face through the point itself. A hit at
    // distance t lies at signed offset t − lead from the point.
    const std::size_t a = static_cast<std::size_t>(axis);
    const float start = std::min(origin[a], -scene.scale) - 0.5f * scene.scale;
    const double lead = static_cast<double>(origin[a]) - static_cast<double>(start);
    origin[a] = start;
    HitList hits;
    m_impl->gather(scene, origin, axis, 1.0f, FLOAT_INF, hits, counts);
    if (hits.empty())
        return AxisOutcome::NO_HIT;

    // The closest crossing in either direction, and every hit that coincides with it.
    std::size_t closest = 0;
    double closest_distance = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < hits.size(); ++i) {
        const double distance = std::abs(static_cast<double>(hits[i].t) - lead);
        if (distance < closest_distance) {
            closest_distance = distance;
            closest = i;
        }
    }
    const Hit& hit = hits[closest];
    // Magnitude of the float coordinates and distances involved in this ray's hits.
    const double magnitude = static_cast<double>(scene.scale) + lead;
    if (distance_bound != nullptr) // the hit is a surface point, up to float noise
        *distance_bound = closest_distance + 4.0 * T_BAND * magnitude;
    if (closest_distance <= T_BAND * magnitude)
        return AxisOutcome::ON_SURFACE; // the point lies on the surface (within float precision)
    std::size_t coinciding = 0;
    for (std::size_t i = 0; i < hits.size(); ++i)
        if (std::abs(static_cast<double>(hits[i].t) - lead) <= closest_distance + T_BAND * magnitude)
            ++coinciding;
    if (coinciding > 1)
        return AxisOutcome::DEGENERATE; // an edge or vertex shared by several faces, or a double layer
    if (distance_to_edge(scene, hit) <= EDGE_BAND * magnitude)
        return AxisOutcome::DEGENERATE; // on an edge: the neighbour face may have been skipped

    const float ng_axis = NG_ALONG_WINDING * hit.ng[a];
    if (std::abs(ng_axis) <= PARALLEL_BAND * norm(hit.ng))
        return AxisOutcome::DEGENERATE; // face (nearly) parallel to the axis
    // d = ±e_axis from the point toward the face; d·n > 0 ⇒ the line leaves the body there ⇒ inside
    const bool ahead = static_cast<double>(hit.t) > lead;
    const float d_dot_n = ahead ? ng_axis : -ng_axis;
    return d_dot_n > 0.0f ? AxisOutcome::INSIDE : AxisOutcome::OUTSIDE;
}

InsideTest EmbreeSceneSet::inside_test(const ContactSurface& surface, Index s, const Vec3& point,
                                       EmbreeQueryCounts* counts) const
{
    // The deciding axis's closest hit bounds the depth from above (as the axis-ray test's
    // crossing does), so the nearest-point search of the depth starts from it. A bound that float
    // noise made too small only costs a second search (AabbTree::nearest), never the answer.
    double bounds[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                        std::numeric_limits<double>::infinity()};
    InsideTest result = inside_from_axes(
        surface, point, [&](int axis) { return axis_test(s, point, axis, counts, &bounds[axis]); });
    if (result.inside && axis_of(result.decided_by) >= 0)
        result.surface_distance_bound = bounds[axis_of(result.decided_by)];
    return result;
}

namespace {

/// The state of one point query: the query point in double, the best face so far.
struct NearestQuery {
    const ContactSurface* surface;
    Vec3 point;
    double best_d2;  ///< squared distance of the best face, or the initial bound
    NearestPoint best;
    double band;     ///< added to the query radius: Embree's float boxes and query point
};

/// Query radius for a best distance: widened (relative 2⁻²⁰, then the float band) so that no
/// face at that distance in double precision, ties included, lies beyond it in Embree's float
/// coordinates.
float query_radius(double distance, double band)
{
    const double r = distance * (1.0 + 0x1p-20) + band;
    return r < 1e38 ? static_cast<float>(r) : FLOAT_INF;
}

/// Embree's point query callback: measures face primID in double precision with the tree's
/// formula and keeps the smallest (squared distance, face index), as AabbTree::nearest does.
bool nearest_face(RTCPointQueryFunctionArguments* args)
{
    auto& q = *static_cast<NearestQuery*>(args->userPtr);
    const ContactSurface& s = *q.surface;
    const auto f = static_cast<Index>(args->primID);
    const TrianglePoint t = closest_point_on_triangle(q.point, s.vertices.row(s.faces(f, 0)).transpose(),
                                                      s.vertices.row(s.faces(f, 1)).transpose(),
                                                      s.vertices.row(s.faces(f, 2)).transpose());
    const double d2 = (t.point - q.point).squaredNorm();
    if (!(d2 < q.best_d2 || (d2 == q.best_d2 && f < q.best.face)))
        return false;
    q.best_d2 = d2;
    q.best.face = f;
    q.best.point = t.point;
    q.best.barycentric = t.barycentric;
    args->query->radius = query_radius(std::sqrt(d2), q.band);
    return true;
}

} // namespace

NearestPoint EmbreeSceneSet::nearest(const ContactSurface& surface, Index s, const Vec3& point,
                                          double distance_bound) const
{
    CORO_ASSERT(s >= 0 && s < size());
    const SurfaceScene& scene = m_impl->scenes[static_cast<std::size_t>(s)];
    if (scene.num_faces == 0)
        return {};
    const std::array<float, 3> local = scene.local(point);
    CORO_CHECK(std::isfinite(local[0]) && std::isfinite(local[1]) && std::isfinite(local[2]), NumericalError,
               "surface '" << surface.name << "': nearest-point query from a point not finite in float");
    NearestQuery q{&surface, point, std::numeric_limits<double>::infinity(), {}, 0.0};
    // Float noise of the vertices (scale) and of the query point, 64 ulps each as the ray bands.
    const double lead = std::max({std::abs(local[0]), std::abs(local[1]), std::abs(local[2])});
    q.band = 64.0 * FLOAT_EPS * (static_cast<double>(scene.scale) + lead);
    if (distance_bound < std::numeric_limits<double>::infinity()) // inflated as AabbTree::nearest does
        q.best_d2 = distance_bound * distance_bound * (1.0 + 1e-6) + std::numeric_limits<double>::min();
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    RTCPointQuery query;
    query.x = local[0];
    query.y = local[1];
    query.z = local[2];
    query.time = 0.0f;
    query.radius = query_radius(std::sqrt(q.best_d2), q.band);
    rtcPointQuery(scene.scene, &query, &context, nearest_face, &q);
    if (q.best.face < 0) // a bound below the true distance: search again without it
        return distance_bound < std::numeric_limits<double>::infinity()
                   ? nearest(surface, s, point, std::numeric_limits<double>::infinity())
                   : q.best;
    q.best.distance = std::sqrt(q.best_d2);
    return q.best;
}

EmbreeFirstHit EmbreeSceneSet::first_hit(Index s, const Vec3& point, int axis) const
{
    CORO_ASSERT(s >= 0 && s < size() && axis >= 0 && axis < 3);
    const SurfaceScene& scene = m_impl->scenes[static_cast<std::size_t>(s)];
    EmbreeFirstHit result;
    if (scene.num_faces == 0)
        return result;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit ray_hit = axis_ray(scene.local(point), axis, 1.0f, FLOAT_INF);
    rtcIntersect1(scene.scene, &context, &ray_hit);
    if (ray_hit.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return result;
    result.face = static_cast<Index>(ray_hit.hit.primID);
    result.t = ray_hit.ray.tfar;
    result.ng = Vec3(ray_hit.hit.Ng_x, ray_hit.hit.Ng_y, ray_hit.hit.Ng_z);
    return result;
}

double embree_ng_along_winding() { return NG_ALONG_WINDING; }

} // namespace coro::detail
