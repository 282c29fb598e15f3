#pragma once
/// @file contact_response.hpp
/// @brief Penalty contact response (DESIGN.md, Contact response): forces and the matrix terms
/// they add to one linearly implicit Euler step.
///
/// A contact couples the nodes that carry its two points: the penetrating vertex (share −1)
/// and the barycentric point of the other body's face (shares w_i), or a rigid obstacle. With
/// c the shares, n the other surface's outward normal and g ≥ 0 the depth, the gap is
/// g = n·Σ c_k x_k; the penetrating side gets F = k g n + c_n (n·u) n + F_t with u = Σ c_k v_k,
/// and node k gets −c_k F, so the forces of a contact sum to zero. Implicit Euler linearises
/// F around the step start: h² k (c cᵀ ⊗ n nᵀ) and h c_n (c cᵀ ⊗ n nᵀ) enter the matrix.
/// Friction is regularised Coulomb, implicit with a lagged coefficient: F_t = η u_t⁺ with
/// η = μ k g / max(|u_t|, ε) from the step start, i.e. h η (c cᵀ ⊗ (I − n nᵀ)) in the matrix:
/// a slipping contact feels |F_t| ≈ μ k g against its slip, one slower than ε sticks.

#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>
#include <corocontact/core/function_ref.hpp>
#include <corocontact/sim/body.hpp>
#include <corocontact/sim/case_spec.hpp>
#include <corocontact/solver/scene_matrix.hpp>

#include <vector>

namespace coro {

/// Speed [m/s] below which friction sticks (regularised Coulomb).
constexpr double FRICTION_STICK_SPEED = 1e-3;

/// A node carrying part of a contact point, with its barycentric coefficient.
struct ContactShare {
    Index surface = 0;        ///< whose node: a surface index of the evaluation (see ContactNodes)
    Index node = 0;           ///< the node in its body's internal numbering
    double coefficient = 0.0; ///< −1 for the penetrating vertex, w_i on the other face
    bool fixed = false;       ///< the node is held in place
};

/// What one contact adds to the step. With c_r the coefficients of its shares, block (r, s)
/// of the matrix gets c_r c_s K (nothing where either node is fixed: those rows and columns
/// are identity; kept as one ContactCoupling term) and share r's node the force −c_r F.
struct ContactTerms {
    Mat3 stiffness = Mat3::Zero(); ///< K: (h² k + h c_n) n nᵀ plus the friction term [kg]
    Vec3 force = Vec3::Zero();     ///< F = k g n on the penetrating side [N]

    Vec3 force_on(const ContactShare& share) const { return -share.coefficient * force; }
};

/// The terms of a list of contacts and the shares of each: contact i's shares are
/// shares[share_offsets[i] .. share_offsets[i + 1]) (none for a contact of two obstacles).
struct ContactRecords {
    std::vector<ContactTerms> terms;
    std::vector<Index> share_offsets{0};
    std::vector<ContactShare> shares;

    Index size() const { return static_cast<Index>(terms.size()); }
};

/// What the response reads of the nodes under the contact surfaces.
class ContactNodes {
public:
    virtual ~ContactNodes() = default;
    /// Whether surface `surface` is a body's, whose vertices move with nodes; obstacles carry
    /// none.
    virtual bool carries_nodes(Index surface) const = 0;
    /// Velocity of node `node` of that body [m/s].
    virtual Vec3 velocity(Index surface, Index node) const = 0;
    virtual bool fixed(Index surface, Index node) const = 0;
};

/// The nodes of the scene's bodies, surface b being body b's.
class BodyNodes final : public ContactNodes {
public:
    explicit BodyNodes(const std::vector<Body>& bodies) : m_bodies(bodies) {}
    bool carries_nodes(Index surface) const override
    {
        return surface >= 0 && surface < static_cast<Index>(m_bodies.size());
    }
    Vec3 velocity(Index surface, Index node) const override
    {
        return m_bodies[static_cast<std::size_t>(surface)].velocities().segment<3>(3 * node);
    }
    bool fixed(Index surface, Index node) const override
    {
        return m_bodies[static_cast<std::size_t>(surface)].fixed()[static_cast<std::size_t>(node)] != 0;
    }

private:
    const std::vector<Body>& m_bodies;
};

/// The terms and shares of every contact, in parallel over the contacts (each writes its own
/// slots, so the result does not depend on the thread count).
/// @param[in] surfaces  the surfaces the contacts index (bodies' and obstacles')
/// @param[in] contacts  detection output (surfaces and plane obstacles, see ContactTarget)
/// @param[in] nodes     velocities and fixed flags of the bodies' nodes
/// @param[in] dt        the step h [s]
/// @param[out] records  one entry per contact, in the contacts' order (capacity is kept)
void evaluate_contacts(const std::vector<ContactSurface>& surfaces, const std::vector<ContactPoint>& contacts,
                       const ContactNodes& nodes, const ContactSettings& settings, double dt,
                       ContactRecords& records);

/// What contact adds to one implicit Euler step of the scene: explicit forces per body (into
/// the caller's vectors, the scene's own), and the coupling terms of the scene matrix.
class ContactResponse {
public:
    /// Builds the response of every contact point, in parallel over the contacts; every
    /// contact writes its own slots, which are then added in contact order, so forces and terms
    /// never depend on the thread count. Buffers are kept between calls (no allocation once they
    /// have held a step's contacts).
    /// @param[in] bodies    the scene's bodies (velocities and fixed nodes are read)
    /// @param[in] surfaces  surfaces of the bodies (same order), then of static obstacles
    /// @param[in] contacts  detection output (surfaces and plane obstacles, see ContactTarget)
    /// @param[in] dt        the step h [s]
    /// @param[in,out] matrix  the scene matrix whose coupling() is refilled and finished (fixed
    ///                        nodes take no part in it)
    /// @param[out] forces     per body, #3V: explicit contact forces at the step start
    ///                        (penalty) [N]; vectors already of the right size are reused
    void compute(const std::vector<Body>& bodies, const std::vector<ContactSurface>& surfaces,
                 const std::vector<ContactPoint>& contacts, const ContactSettings& settings, double dt,
                 SceneMatrix& matrix, std::vector<VecX>& forces);

    /// Adds evaluated contacts to this process's rows, contact after contact in the records'
    /// order: the forces on the nodes of its bodies, and the coupling terms of their rows
    /// (compute() is evaluate_contacts() and this for one process).
    /// @param[in] records     the contacts, in the order one process holding every body adds them
    /// @param[in] bodies      this process's bodies (`forces` is sized by them)
    /// @param[in] local_body  the index in `bodies` of a share's surface, or −1 if another
    ///                        process holds it (its rows are left out)
    /// @param[in] column      the column of a share's node in `matrix`: a row of a body here, or
    ///                        a ghost row after them (see scene_exchange.hpp)
    /// @param[in,out] matrix  its coupling() is refilled and finished
    /// @param[out] forces     per body here, #3V: the forces on its nodes [N]
    void apply(const ContactRecords& records, const std::vector<Body>& bodies,
               FunctionRef<Index(Index surface)> local_body, FunctionRef<Index(Index surface, Index node)> column,
               SceneMatrix& matrix, std::vector<VecX>& forces);

private:
    ContactRecords m_records;
    std::vector<Vec3> m_share_forces;   // force on each share's node, of the shares here [N]
};

} // namespace coro
