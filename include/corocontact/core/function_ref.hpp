#pragma once
/// @file function_ref.hpp
/// @brief A non-owning reference to a callable, for the bodies of parallel loops: unlike
/// std::function it never allocates, so a loop in the time step can take a lambda that
/// captures as much as it likes.

#include <type_traits>
#include <utility>

namespace coro {

template <class Signature> class FunctionRef;

/// Refers to a callable `R(Args...)` that must outlive the FunctionRef (pass a lambda straight
/// to the function that takes it; never store one).
template <class R, class... Args> class FunctionRef<R(Args...)> {
public:
    template <class F, class = std::enable_if_t<!std::is_same_v<std::decay_t<F>, FunctionRef>>>
    FunctionRef(F&& callable) // NOLINT(google-explicit-constructor): converts like std::function
        : m_object(const_cast<void*>(static_cast<const void*>(&callable))),
          m_call([](void* object, Args... args) -> R {
              return (*static_cast<std::remove_reference_t<F>*>(object))(std::forward<Args>(args)...);
          })
    {
    }

    R operator()(Args... args) const { return m_call(m_object, std::forward<Args>(args)...); }

private:
    void* m_object;
    R (*m_call)(void*, Args...);
};

} // namespace coro
