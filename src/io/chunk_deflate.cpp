#include "chunk_deflate.hpp"

#include <libdeflate.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "h5_util.hpp"

namespace hypershape::io {

namespace {

struct CompressorDeleter {
  void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
};

/// One compressor per thread, kept: its allocation is larger than a small array's chunk.
libdeflate_compressor* compressor() {
  thread_local std::unique_ptr<libdeflate_compressor, CompressorDeleter> c(
      libdeflate_alloc_compressor(kDeflateLevel));
  if (!c) throw std::runtime_error("libdeflate: cannot allocate a compressor");
  return c.get();
}

/// HDF5's shuffle filter (H5Z_FILTER_SHUFFLE): byte j of element i goes to j * count + i; a
/// one-byte type is left as it is, as the filter leaves it.
void shuffle(const unsigned char* in, std::size_t count, std::size_t elem, unsigned char* out) {
  if (elem == 1) {
    std::memcpy(out, in, count);
    return;
  }
  for (std::size_t j = 0; j < elem; ++j) {
    unsigned char* o = out + j * count;
    for (std::size_t i = 0; i < count; ++i) o[i] = in[i * elem + j];
  }
}

}  // namespace

void write_deflated_chunks(hid_t ds, const void* data, const std::vector<hsize_t>& dims,
                           const std::vector<hsize_t>& chunk, std::size_t elem) {
  std::size_t row = elem;  // bytes of one index along the first axis
  for (std::size_t a = 1; a < dims.size(); ++a) row *= std::size_t(dims[a]);
  const std::size_t rows = std::size_t(chunk[0]), bytes = rows * row;
  // A chunk past the end of the first axis is stored whole, its tail zero (never read).
  std::vector<unsigned char> whole(bytes), shuffled(bytes);
  std::vector<unsigned char> packed(libdeflate_zlib_compress_bound(compressor(), bytes));
  std::vector<hsize_t> offset(dims.size(), 0);
  const auto* src = static_cast<const unsigned char*>(data);
  for (hsize_t r0 = 0; r0 < dims[0]; r0 += chunk[0]) {
    const std::size_t n = std::min<std::size_t>(rows, std::size_t(dims[0] - r0)) * row;
    std::memcpy(whole.data(), src + std::size_t(r0) * row, n);
    std::fill(whole.begin() + std::ptrdiff_t(n), whole.end(), 0);
    shuffle(whole.data(), bytes / elem, elem, shuffled.data());
    const std::size_t size = libdeflate_zlib_compress(compressor(), shuffled.data(), bytes, packed.data(), packed.size());
    if (size == 0) throw std::runtime_error("libdeflate: a chunk did not fit its bound");
    offset[0] = r0;
    check(H5Dwrite_chunk(ds, H5P_DEFAULT, 0, offset.data(), size, packed.data()), "write a chunk");
  }
}

std::uint32_t crc32_update(std::uint32_t crc, const void* bytes, std::size_t n) {
  return libdeflate_crc32(crc, bytes, n);
}

}  // namespace hypershape::io
