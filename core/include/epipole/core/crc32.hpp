#pragma once

#include <cstdint>
#include <span>

namespace epipole {

// CRC-32 as in Ethernet, zlib and PNG (reflected polynomial 0xEDB88320, initial and final
// value 0xFFFFFFFF): crc32("123456789") = 0xCBF43926. Used by the serial protocol's frames and
// the compiled cascade format. `previous` continues a CRC: crc32(b, crc32(a)) is the CRC of a
// followed by b.
std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t previous = 0);

}  // namespace epipole
