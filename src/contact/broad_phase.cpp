#include <corocontact/contact/broad_phase.hpp>

#include <algorithm>

namespace coro {

std::vector<std::pair<Index, Index>> overlapping_pairs(const std::vector<Aabb>& boxes)
{
    std::vector<Index> order;
    order.reserve(boxes.size());
    Aabb centres;
    for (std::size_t i = 0; i < boxes.size(); ++i)
        if (!boxes[i].empty()) {
            order.push_back(static_cast<Index>(i));
            centres.extend(Vec3(0.5 * (boxes[i].min + boxes[i].max)));
        }
    std::vector<std::pair<Index, Index>> pairs;
    if (order.size() < 2)
        return pairs;

    // Sweep along the axis in which the centres spread most: boxes are sorted by their lower end;
    // a box leaves the active set once the sweep passes its upper end (closed intervals, so a box
    // that only touches the next one stays).
    int axis = 0;
    (centres.max - centres.min).maxCoeff(&axis);
    const auto box = [&](Index i) -> const Aabb& { return boxes[static_cast<std::size_t>(i)]; };
    std::sort(order.begin(), order.end(), [&](Index a, Index b) {
        return box(a).min[axis] < box(b).min[axis] || (box(a).min[axis] == box(b).min[axis] && a < b);
    });
    std::vector<Index> active;
    for (const Index i : order) {
        const double lower = box(i).min[axis];
        active.erase(std::remove_if(active.begin(), active.end(),
                                    [&](Index j) { return box(j).max[axis] < lower; }),
                     active.end());
        for (const Index j : active)
            if (box(i).overlaps(box(j)))
                pairs.emplace_back(std::min(i, j), std::max(i, j));
        active.push_back(i);
    }
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

} // namespace coro
