// Each row of the half neighbour list ordered with its contacts first (dem_system.hpp), shared
// by the frictionless pair loop (pair_loop.cpp) and the frictional one (dem_system.cpp): a row's
// entries that touch first, then the others, each part in the list's order, so that a loop
// over the first part meets the contacts in the order the sums must take
// (docs/performance.md "Contacts first in each row"). Internal to the dem module's sources.
#pragma once

#include <cstdint>

namespace rendulic::dem {

// Row [begin, end) of the list written to `first` as value(e) of each entry e: those with
// touches(e) first, then the others, each part in the list's order. Returns the end of the
// first part.
template <class Out, class Value, class Touches>
std::int64_t contacts_first(Out* first, std::int64_t begin, std::int64_t end, Value&& value,
                            Touches&& touches) {
  std::int64_t w = begin;
  for (std::int64_t e = begin; e < end; ++e)
    if (touches(e)) first[w++] = value(e);
  const std::int64_t split = w;
  for (std::int64_t e = begin; e < end; ++e)
    if (!touches(e)) first[w++] = value(e);
  return split;
}

}  // namespace rendulic::dem
