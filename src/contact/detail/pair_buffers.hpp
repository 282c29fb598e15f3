#pragma once
/// @file pair_buffers.hpp
/// @brief Per-pair items that own buffers (vectors), kept from detection to detection: an item
/// stays with its pair of surfaces while the pair lasts, and the items of pairs gone serve the
/// pairs that come (most recently dropped first: a pair that parts and meets again, as pairs at
/// rest do, mostly gets its own back). So a time loop allocates only when there are more pairs
/// than ever or a pair outgrows the buffers it holds.

#include <corocontact/core/types.hpp>

#include <utility>
#include <vector>

namespace coro::detail {

template <class T>
class PairBuffers {
public:
    using Key = std::pair<Index, Index>;

    /// The items of `keys` (ascending, distinct), in their order. An item whose key the last call
    /// had is as that call left it; the others hold what some earlier item held (stale: the
    /// caller overwrites what it uses).
    std::vector<T>& assign(const std::vector<Key>& keys)
    {
        // A merge of the last keys with the new ones.
        m_next.clear(); // shells whose buffers moved on
        std::size_t j = 0;
        for (const Key& key : keys) {
            for (; j < m_keys.size() && m_keys[j] < key; ++j)
                m_spare.push_back(std::move(m_items[j]));
            if (j < m_keys.size() && m_keys[j] == key) {
                m_next.push_back(std::move(m_items[j++]));
            } else if (!m_spare.empty()) {
                m_next.push_back(std::move(m_spare.back()));
                m_spare.pop_back();
            } else {
                m_next.emplace_back();
            }
        }
        for (; j < m_keys.size(); ++j)
            m_spare.push_back(std::move(m_items[j]));
        m_items.swap(m_next);
        m_keys = keys;
        return m_items;
    }

    std::vector<T>& items() { return m_items; }
    const std::vector<T>& items() const { return m_items; }

private:
    std::vector<Key> m_keys; // of m_items
    std::vector<T> m_items;
    std::vector<T> m_next;  // the next call's items while it sorts them out
    std::vector<T> m_spare; // items of pairs gone, with their buffers
};

} // namespace coro::detail
