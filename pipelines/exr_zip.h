// The chunks of OpenEXR's ZIP_COMPRESSION, encoded here rather than by OpenEXR, because the
// rendered frames are nearly all flat: background, and surfaces whose values repeat along the
// line or from one line to the next. zlib spent ~200 us a 16-line chunk on such data whatever
// it held (it compares every byte of every match); a deflate encoder that only looks for those
// repeats does the same job in a fraction of that (bench/pipelines_bench.cc,
// BM_WriteExrChannels640x480: the whole frame against OpenEXR's own writer).
//
// A chunk (ImfZip.cpp; OpenEXR file layout): the lines' bytes split into the even and the odd
// ones, each byte replaced by its difference to the byte before plus 128, then a zlib stream
// (RFC 1950/1951). A chunk that would not shrink is stored as it is (readers tell by its size).
#pragma once

#include <cstddef>
#include <vector>

namespace wobble::pipelines {

// Encodes one chunk: `raw` holds its lines as the file stores them, `line_bytes` each (for the
// match one line up). The stream is deflate with fixed Huffman codes whose only matches are
// repeats at distances 1, 2, 3, 4, 6 and 8 bytes (a flat channel) and one line up; where that
// does not shrink the chunk to an eighth, zlib (level 1) encodes it instead, and where neither
// shrinks it, `out` is `raw`. `scratch` is reused between calls.
void EncodeZipChunk(const unsigned char* raw, size_t n, size_t line_bytes, std::vector<unsigned char>* scratch,
                    std::vector<unsigned char>* out);

// The encoded bytes of chunks this thread encoded before, reused for a chunk with the same raw
// bytes: the same chunk of its previous file, or the chunk above in this file. 61% of the demo's
// frame chunks repeat (background). Encoded bytes depend on the raw bytes alone, so a match is
// exact. Keeps at most 64 MiB of raw chunks; past that, chunks are encoded every time.
class ZipChunkCache {
 public:
  const std::vector<unsigned char>& Encoded(size_t chunk, const unsigned char* raw, size_t n, size_t line_bytes);

 private:
  static constexpr size_t kBytes = size_t(64) << 20;
  struct Chunk {
    std::vector<unsigned char> raw, encoded;
  };
  std::vector<Chunk> chunks_;
  std::vector<unsigned char> scratch_, uncached_;
};

}  // namespace wobble::pipelines
