#pragma once
/// @file element_loop.hpp
/// @brief The parallel loop over parts: one TBB task per part.

#include <corocontact/core/types.hpp>

#include <functional>

namespace coro {

/// Calls `work(part)` for every part in [0, num_parts), in parallel (one task per part).
/// Work inside a part is serial, so anything a part writes only to its own data is
/// deterministic whatever the thread count.
void for_each_part(Index num_parts, const std::function<void(Index part)>& work);

} // namespace coro
