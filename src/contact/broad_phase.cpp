#include <corocontact/contact/broad_phase.hpp>

#include <algorithm>

namespace coro {

void overlapping_pairs(const std::vector<Aabb>& boxes, std::vector<std::pair<Index, Index>>& pairs,
                       std::vector<Index>& order)
{
    pairs.clear();
    order.clear();
    Aabb centres;
    for (std::size_t i = 0; i < boxes.size(); ++i)
        if (!boxes[i].empty()) {
            order.push_back(static_cast<Index>(i));
            centres.extend(Vec3(0.5 * (boxes[i].min + boxes[i].max)));
        }
    if (order.size() < 2)
        return;

    // Sweep along the axis in which the centres spread most: boxes are sorted by their lower end;
    // each box meets those after it in that order up to the first whose lower end lies beyond its
    // upper end (closed intervals, so a box that only touches the next one meets it).
    int axis = 0;
    (centres.max - centres.min).maxCoeff(&axis);
    const auto box = [&](Index i) -> const Aabb& { return boxes[static_cast<std::size_t>(i)]; };
    std::sort(order.begin(), order.end(), [&](Index a, Index b) {
        return box(a).min[axis] < box(b).min[axis] || (box(a).min[axis] == box(b).min[axis] && a < b);
    });
    for (std::size_t p = 0; p < order.size(); ++p) {
        const Index i = order[p];
        const double upper = box(i).max[axis];
        for (std::size_t q = p + 1; q < order.size() && !(box(order[q]).min[axis] > upper); ++q) {
            const Index j = order[q];
            if (box(i).overlaps(box(j)))
                pairs.emplace_back(std::min(i, j), std::max(i, j));
        }
    }
    std::sort(pairs.begin(), pairs.end());
}

std::vector<std::pair<Index, Index>> overlapping_pairs(const std::vector<Aabb>& boxes)
{
    std::vector<std::pair<Index, Index>> pairs;
    std::vector<Index> order;
    overlapping_pairs(boxes, pairs, order);
    return pairs;
}

} // namespace coro
