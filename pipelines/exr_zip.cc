#include "pipelines/exr_zip.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>

namespace wobble::pipelines {
namespace {

// A Huffman code (or code and extra bits) ready to be written: deflate sends codes from their
// first bit on, into bytes filled from the low bit (RFC 1951, 3.1.1), so codes are stored reversed.
struct Bits {
  std::uint32_t value = 0;
  int count = 0;
};

std::uint32_t Reversed(std::uint32_t code, int count) {
  std::uint32_t r = 0;
  for (int i = 0; i < count; ++i) r |= ((code >> i) & 1u) << (count - 1 - i);
  return r;
}

// The fixed literal/length code (RFC 1951, 3.2.6).
Bits FixedCode(int symbol) {
  if (symbol < 144) return {Reversed(0x30u + symbol, 8), 8};
  if (symbol < 256) return {Reversed(0x190u + (symbol - 144), 9), 9};
  if (symbol < 280) return {Reversed(std::uint32_t(symbol - 256), 7), 7};
  return {Reversed(0xC0u + (symbol - 280), 8), 8};
}

// Lengths 3..258 and distances 1..32768: code, first value, extra bits (RFC 1951, 3.2.5).
constexpr std::array<int, 29> kLengthBase = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                             31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
constexpr std::array<int, 29> kLengthExtra = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                              2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
constexpr std::array<int, 30> kDistanceBase = {1,   2,   3,   4,   5,   7,    9,    13,   17,   25,
                                               33,  49,  65,  97,  129, 193,  257,  385,  513,  769,
                                               1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
constexpr std::array<int, 30> kDistanceExtra = {0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6,
                                                6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};
constexpr size_t kMinMatch = 3, kMaxMatch = 258, kWindow = 32768;

struct FixedTables {
  std::array<Bits, 256> literal;
  std::array<Bits, kMaxMatch + 1> length;  // code and extra bits, for lengths 3..258
  Bits end;
  FixedTables() {
    for (int b = 0; b < 256; ++b) literal[size_t(b)] = FixedCode(b);
    for (int code = 0; code < 29; ++code) {
      // 258 has a code of its own (285), though 284's extra bits could also say it
      const int last = code < 28 ? kLengthBase[size_t(code) + 1] - 1 : 258;
      for (int len = kLengthBase[size_t(code)]; len <= last; ++len) {
        const Bits c = FixedCode(257 + code);
        length[size_t(len)] = {c.value | std::uint32_t(len - kLengthBase[size_t(code)]) << c.count,
                               c.count + kLengthExtra[size_t(code)]};
      }
    }
    end = FixedCode(256);
  }
};

Bits DistanceCode(size_t distance) {
  int code = 29;
  while (kDistanceBase[size_t(code)] > int(distance)) --code;
  // fixed distance codes are the 5-bit code numbers
  return {Reversed(std::uint32_t(code), 5) | std::uint32_t(int(distance) - kDistanceBase[size_t(code)]) << 5,
          5 + kDistanceExtra[size_t(code)]};
}

class BitWriter {
 public:
  BitWriter(unsigned char* out, unsigned char* limit) : out_(out), limit_(limit) {}
  void Put(Bits b) {
    bits_ |= std::uint64_t(b.value) << count_;
    count_ += b.count;
    if (count_ >= 32) {
      for (int i = 0; i < 4; ++i) *out_++ = (unsigned char)(bits_ >> (8 * i));
      bits_ >>= 32;
      count_ -= 32;
    }
  }
  bool Over() const { return out_ >= limit_; }
  unsigned char* Flush() {  // the last bits, padded to a byte
    for (; count_ > 0; count_ -= 8, bits_ >>= 8) *out_++ = (unsigned char)bits_;
    count_ = 0;
    return out_;
  }

 private:
  unsigned char* out_;
  unsigned char* limit_;
  std::uint64_t bits_ = 0;
  int count_ = 0;
};

// How many bytes from `a` on equal those from `b` on, up to `limit`.
size_t MatchLength(const unsigned char* a, const unsigned char* b, size_t limit) {
  size_t k = 0;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  for (; k + 8 <= limit; k += 8) {
    std::uint64_t x, y;
    std::memcpy(&x, a + k, 8);
    std::memcpy(&y, b + k, 8);
    if (x != y) return k + size_t(__builtin_ctzll(x ^ y) / 8);  // the first differing byte
  }
#endif
  while (k < limit && a[k] == b[k]) ++k;
  return k;
}

// zlib stream of `data` with fixed codes and matches at the given distances only, greedy
// (the longest match at each byte). False when it would take `budget` bytes or more.
bool RepeatsDeflate(const unsigned char* data, size_t n, const std::vector<size_t>& distances, size_t budget,
                    std::vector<unsigned char>* out) {
  static const FixedTables tables;
  out->resize(budget + 16);  // the writer stops at `budget`; one symbol and the end past it
  (*out)[0] = 0x78;          // deflate, 32 KiB window (RFC 1950)
  (*out)[1] = 0x01;          // fastest, no dictionary; 0x7801 is a multiple of 31
  BitWriter w(out->data() + 2, out->data() + budget - 4);
  w.Put({3, 3});  // the last block, fixed Huffman codes (RFC 1951, 3.2.3)
  std::vector<Bits> codes;
  for (size_t d : distances) codes.push_back(DistanceCode(d));
  size_t i = 0;
  while (i < n) {
    if (w.Over()) return false;
    const size_t limit = std::min(kMaxMatch, n - i);
    size_t best = 0, which = 0;
    for (size_t k = 0; k < distances.size() && best < limit; ++k) {
      if (distances[k] > i) continue;
      const size_t len = MatchLength(data + i, data + i - distances[k], limit);
      if (len > best) {
        best = len;
        which = k;
      }
    }
    if (best >= kMinMatch) {
      w.Put(tables.length[best]);
      w.Put(codes[which]);
      i += best;
    } else {
      w.Put(tables.literal[data[i]]);
      ++i;
    }
  }
  w.Put(tables.end);
  unsigned char* end = w.Flush();
  if (end + 4 > out->data() + budget) return false;
  const uLong check = adler32(adler32(0, nullptr, 0), data, uInt(n));  // big-endian (RFC 1950)
  for (int s = 24; s >= 0; s -= 8) *end++ = (unsigned char)(check >> s);
  out->resize(size_t(end - out->data()));
  return true;
}

}  // namespace

void EncodeZipChunk(const unsigned char* raw, size_t n, size_t line_bytes, std::vector<unsigned char>* scratch,
                    std::vector<unsigned char>* out) {
  if (n == 0) return out->clear();
  scratch->resize(2 * n);
  unsigned char* split = scratch->data();
  unsigned char* even = split;
  unsigned char* odd = split + (n + 1) / 2;
  for (size_t i = 0; i < n / 2; ++i) {
    even[i] = raw[2 * i];
    odd[i] = raw[2 * i + 1];
  }
  if (n % 2) even[n / 2] = raw[n - 1];
  unsigned char* predicted = split + n;
  predicted[0] = split[0];
  for (size_t i = 1; i < n; ++i) predicted[i] = (unsigned char)(split[i] - split[i - 1] + 128);

  // a flat channel repeats its 1, 2 or 4 bytes (halves, floats: split in two), or 3 and 6, 8
  // (a run of pixels of one colour); a line like the one above repeats half a line back
  std::vector<size_t> distances = {1, 2, 4, 8, 3, 6};
  if (line_bytes / 2 > 8 && line_bytes / 2 <= kWindow) distances.insert(distances.begin() + 1, line_bytes / 2);
  if (n >= 1024 && RepeatsDeflate(predicted, n, distances, n / 8, out)) return;
  out->resize(compressBound(uLong(n)));
  uLongf size = uLongf(out->size());
  if (compress2(out->data(), &size, predicted, uLong(n), 1) != Z_OK || size >= n) {
    out->assign(raw, raw + n);
    return;
  }
  out->resize(size);
}

const std::vector<unsigned char>& ZipChunkCache::Encoded(size_t chunk, const unsigned char* raw, size_t n,
                                                        size_t line_bytes) {
  if (chunks_.size() <= chunk) chunks_.resize(chunk + 1);
  Chunk& c = chunks_[chunk];
  auto same = [&](const Chunk& o) { return o.raw.size() == n && std::memcmp(o.raw.data(), raw, n) == 0; };
  if (same(c)) return c.encoded;
  if (chunk > 0 && same(chunks_[chunk - 1])) {
    c = chunks_[chunk - 1];
    return c.encoded;
  }
  if (n * (chunk + 1) > kBytes) {  // an image too large to keep
    c = Chunk();
    EncodeZipChunk(raw, n, line_bytes, &scratch_, &uncached_);
    return uncached_;
  }
  c.raw.assign(raw, raw + n);
  EncodeZipChunk(raw, n, line_bytes, &scratch_, &c.encoded);
  return c.encoded;
}

}  // namespace wobble::pipelines
