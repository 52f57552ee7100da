#pragma once

// Each message's wire layout, written once in its struct (protocol/messages.hpp): its static
// fields(io, m) visits the fields in wire order, with their names. The encoder, the decoder and
// the host tool's JSON output are all visitors of these lists.
//
// A visitor `io` provides:
//   io(name, value)                        one number (or enum of one byte)
//   io.list(name, count, limit, items, f)  a u8 count (at most limit), then f(io, items[i])
//                                          for each of the first count items
#include <type_traits>

#include "epipole/firmware/protocol/messages.hpp"

namespace epipole::protocol {

template <class Io, class M>
void fields(Io& io, M& m) {
  std::remove_const_t<M>::fields(io, m);
}

}  // namespace epipole::protocol
