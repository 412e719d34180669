#pragma once
/// Chunked datasets written with their shuffle and deflate filters applied here (internal to
/// src/io/): libdeflate compresses a chunk about twice as fast as the zlib that HDF5's own
/// deflate filter calls, and at level 4 into as few bytes or fewer. The chunks are stored as
/// HDF5 would store them (H5Dwrite_chunk, filter mask 0), so every reader decodes them with
/// the standard filters the dataset declares: the same arrays, other bytes on disk.
#include <hdf5.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hypershape::io {

/// The DEFLATE level of every shard array (the dataset's declared filter says the same).
inline constexpr int kDeflateLevel = 4;

/// Declares on the dataset creation list `dcpl` what write_deflated_chunks applies: chunks of
/// `chunk` (equal to the dataset's dims past the first axis), the shuffle, then deflate at
/// kDeflateLevel. `what` names the dataset in an error.
void declare_deflated_chunks(hid_t dcpl, const std::vector<hsize_t>& chunk, const std::string& what);

/// Writes the whole of `data` (row-major, `dims`) into the chunked dataset `ds`, created with
/// declare_deflated_chunks(`chunk`); `elem` is the bytes of one element.
void write_deflated_chunks(hid_t ds, const void* data, const std::vector<hsize_t>& dims,
                           const std::vector<hsize_t>& chunk, std::size_t elem);

/// CRC-32 (zlib's polynomial) of `n` bytes, continuing `crc` (0 to start).
std::uint32_t crc32_update(std::uint32_t crc, const void* bytes, std::size_t n);

}  // namespace hypershape::io
