// wobble's encoder of OpenEXR ZIP chunks (pipelines/exr_zip.h) against zlib's inflate: every
// chunk must inflate to the bytes OpenEXR's ZIP_COMPRESSION deflates (the lines split into even
// and odd bytes, then byte differences plus 128; ImfZip.cpp), computed here on their own, for
// flat, repeating, noisy and random-structured chunks that reach every length and distance code.
#include <gtest/gtest.h>
#include <zlib.h>

#include <random>
#include <vector>

#include "pipelines/exr_zip.h"

namespace wobble::pipelines {
namespace {

using Bytes = std::vector<unsigned char>;

Bytes Predicted(const Bytes& raw) {
  Bytes split;
  for (size_t i = 0; i < raw.size(); i += 2) split.push_back(raw[i]);
  for (size_t i = 1; i < raw.size(); i += 2) split.push_back(raw[i]);
  Bytes out(split.size());
  for (size_t i = 0; i < split.size(); ++i) out[i] = i == 0 ? split[0] : (unsigned char)(split[i] - split[i - 1] + 128);
  return out;
}

// What a reader does with a chunk: stored as it is when it did not shrink, else inflated.
Bytes Decoded(const Bytes& chunk, size_t n) {
  if (chunk.size() == n) return chunk;
  Bytes out(n + 1);
  uLongf size = uLongf(out.size());
  EXPECT_EQ(uncompress(out.data(), &size, chunk.data(), uLong(chunk.size())), Z_OK);
  out.resize(size);
  return out;
}

void ExpectRoundTrip(const Bytes& raw, size_t line_bytes, const std::string& what, Bytes* encoded = nullptr) {
  Bytes scratch, out;
  EncodeZipChunk(raw.data(), raw.size(), line_bytes, &scratch, &out);
  ASSERT_LE(out.size(), raw.size()) << what;
  if (out.size() == raw.size()) {
    EXPECT_EQ(out, raw) << what << ": stored, so as it is";
  } else {
    EXPECT_EQ(Decoded(out, raw.size()), Predicted(raw)) << what;
  }
  if (encoded) *encoded = out;
}

// A 16-line chunk of a 640-pixel frame: 7 half channels and a float one, 10240 bytes a line.
constexpr size_t kLine = 10240, kChunk = 16 * kLine;

bool FixedCodes(const Bytes& chunk) { return chunk.size() > 2 && (chunk[2] & 7) == 3; }  // last block, fixed

TEST(ZipChunk, FlatAndRepeatingChunksTakeTheRepeatsEncoder) {
  Bytes zeros(kChunk, 0), encoded;
  ExpectRoundTrip(zeros, kLine, "zeros", &encoded);
  EXPECT_TRUE(FixedCodes(encoded));
  EXPECT_LT(encoded.size(), kChunk / 100);
  // a line of smooth halves and floats, the same on every line of the chunk
  Bytes rows(kChunk);
  for (size_t i = 0; i < kLine; ++i) rows[i] = (unsigned char)(i < 8 * 640 ? (i / 7) % 256 : (i % 4 == 3 ? 0x43 : i % 13));
  for (size_t r = 1; r < 16; ++r) std::copy_n(rows.begin(), kLine, rows.begin() + long(r * kLine));
  ExpectRoundTrip(rows, kLine, "repeated lines", &encoded);
  EXPECT_TRUE(FixedCodes(encoded));
  EXPECT_LT(encoded.size(), kChunk / 8);
}

TEST(ZipChunk, NoiseIsStoredAndTextureGoesToZlib) {
  std::mt19937 random(7);
  Bytes noise(kChunk);
  for (unsigned char& b : noise) b = (unsigned char)random();
  Bytes encoded;
  ExpectRoundTrip(noise, kLine, "noise", &encoded);
  EXPECT_EQ(encoded, noise);
  // four symbols in random order: no repeats to find, but zlib's Huffman codes halve it
  Bytes texture(kChunk);
  for (unsigned char& b : texture) b = (unsigned char)(random() % 4);
  ExpectRoundTrip(texture, kLine, "texture", &encoded);
  EXPECT_LT(encoded.size(), kChunk / 2);
  EXPECT_FALSE(FixedCodes(encoded));
}

TEST(ZipChunk, RandomStructureInflatesExactly) {
  // runs of every length (3 to 258 and past it), copies of the line above, short repeats and
  // noise, in random mixtures and sizes (odd ones, and ones below the encoder's minimum)
  std::mt19937 random(11);
  int repeats_encoder = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const size_t line = 2 * (1 + random() % 3000);
    const size_t n = trial % 10 == 0 ? random() % 1500 : line * (1 + random() % 16) + (trial % 7 == 0 ? 1 : 0);
    Bytes raw;
    while (raw.size() < n) {
      const int kind = int(random() % 4);
      const size_t len = 1 + random() % 400;
      if (kind == 0) {
        raw.insert(raw.end(), len, (unsigned char)random());
      } else if (kind == 1 && raw.size() >= line) {
        for (size_t k = 0; k < len; ++k) raw.push_back(raw[raw.size() - line]);
      } else if (kind == 2) {
        const unsigned char a = (unsigned char)random(), b = (unsigned char)random(), c = (unsigned char)random();
        for (size_t k = 0; k < len; ++k) raw.push_back(k % 3 == 0 ? a : k % 3 == 1 ? b : c);
      } else {
        for (size_t k = 0; k < len % 40; ++k) raw.push_back((unsigned char)random());
      }
    }
    raw.resize(n);
    Bytes encoded;
    ExpectRoundTrip(raw, line, "trial " + std::to_string(trial), &encoded);
    if (HasFatalFailure() || HasNonfatalFailure()) return;
    repeats_encoder += FixedCodes(encoded) && encoded.size() < raw.size();
  }
  EXPECT_GT(repeats_encoder, 100) << "mostly zlib: the repeats encoder was hardly tested";
}

}  // namespace
}  // namespace wobble::pipelines
