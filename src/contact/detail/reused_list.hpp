#pragma once
/// @file reused_list.hpp
/// @brief A list whose items own buffers (vectors) and whose length changes from call to call:
/// the items dropped keep their buffers for the items added later, so that a time loop allocates
/// only when the list grows past its longest or an item past its largest.

#include <utility>
#include <vector>

namespace coro::detail {

template <class T>
class ReusedList {
public:
    /// The list, with n items: the first of them as the last call left them, the others with
    /// the content of some earlier item (stale: the caller overwrites what it uses).
    std::vector<T>& resize(std::size_t n)
    {
        while (m_items.size() > n) {
            m_spare.push_back(std::move(m_items.back()));
            m_items.pop_back();
        }
        while (m_items.size() < n) {
            if (m_spare.empty()) {
                m_items.emplace_back();
            } else {
                m_items.push_back(std::move(m_spare.back()));
                m_spare.pop_back();
            }
        }
        return m_items;
    }

    std::vector<T>& items() { return m_items; }
    const std::vector<T>& items() const { return m_items; }

private:
    std::vector<T> m_items;
    std::vector<T> m_spare; // items dropped, with their buffers
};

} // namespace coro::detail
