// fdem/common/field_count.hpp: the number of fields of an aggregate (a struct without constructors, bases or
// private fields), at compile time: the largest n for which T{f_1, ..., f_n} compiles, each f_i an object that
// converts to any type. A C array field counts as its elements (brace elision): use std::array in a counted struct.
#pragma once

#include <cstddef>
#include <type_traits>
#include <utility>

namespace fdem {

namespace field_count_detail {

struct AnyField {
    template <class T>
    operator T() const;  // (only named in unevaluated operands)
};

template <class T, class Seq, class = void>
struct Braces : std::false_type {};
template <class T, std::size_t... I>
struct Braces<T, std::index_sequence<I...>, std::void_t<decltype(T{(static_cast<void>(I), AnyField{})...})>>
    : std::true_type {};

template <class T, std::size_t N>
constexpr std::size_t count() {
    if constexpr (Braces<T, std::make_index_sequence<N + 1>>::value)
        return count<T, N + 1>();
    else
        return N;
}

}  // namespace field_count_detail

template <class T>
constexpr std::size_t field_count() {
    static_assert(std::is_aggregate_v<T>, "field_count: aggregates only");
    return field_count_detail::count<T, 0>();
}

}  // namespace fdem
