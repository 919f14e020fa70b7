#!/usr/bin/env python3
"""Generate the zlib test vectors of test_zlib.cpp with an independent deflate implementation
(CPython's zlib module). Run once; the outputs are committed:

    python3 tests/mat/gen_zlib_vectors.py tests/mat/vectors

Writes <name>.zz (the stream) for each case and manifest.txt with one line per case:
    <name> <raw|zlib> <inflated size> <crc32 of the inflated bytes, hex>
The C++ test inflates each stream and compares size and CRC-32 (computed by the test's own
CRC-32, not by the code under test). Data is deterministic (fixed seeds).
"""
import os
import random
import struct
import sys
import zlib


def random_bytes(n, seed):
    r = random.Random(seed)
    return bytes(r.getrandbits(8) for _ in range(n))


def text_bytes(n, seed):
    r = random.Random(seed)
    words = [b"allan", b"deviation", b"gyro", b"bias", b"instability", b"random", b"walk",
             b"angle", b"rate", b"quantization", b"noise", b"the", b"of", b"and", b"imu"]
    out = bytearray()
    while len(out) < n:
        out += r.choice(words) + (b"\n" if r.random() < 0.1 else b" ")
    return bytes(out[:n])


def walk_doubles(n, seed):
    """IMU-like: doubles that are integer multiples of an LSB around an offset."""
    r = random.Random(seed)
    lsb = 0.0326955  # 3.33 mg in m/s^2
    return b"".join(struct.pack("<d", (-305 + r.randint(-3, 3)) * lsb) for _ in range(n))


def skewed_bytes(n, seed):
    """Byte frequencies in a Fibonacci ratio: the Huffman code lengths reach deflate's 15-bit
    limit, so the decoder's second-level (sub-)tables and long distance codes are exercised."""
    r = random.Random(seed)
    weights = [1, 1]
    while len(weights) < 24:
        weights.append(weights[-1] + weights[-2])
    symbols = list(range(24))
    out = bytearray(r.choices(symbols, weights=weights[::-1], k=n))
    for i in range(0, n - 64, 997):  # scattered copies at many distances
        j = r.randrange(0, i + 1)
        out[i:i + 40] = out[j:j + 40]
    return bytes(out)


def deflate(data, level, strategy=zlib.Z_DEFAULT_STRATEGY, wbits=15, memlevel=8):
    c = zlib.compressobj(level, zlib.DEFLATED, wbits, memlevel, strategy)
    return c.compress(data) + c.flush()


def main(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    rnd = random_bytes(4096, 1)
    txt = text_bytes(20000, 2)
    rep = b"abc" * 20000
    walk = walk_doubles(32768, 3)  # 256 KiB: several dynamic blocks
    cases = []
    for level in (0, 1, 6, 9):
        cases.append(("empty_l%d" % level, "zlib", b"", deflate(b"", level)))
        cases.append(("text_l%d" % level, "zlib", txt, deflate(txt, level)))
    for level in (0, 9):  # incompressible: zlib falls back to stored blocks at every level
        cases.append(("random4k_l%d" % level, "zlib", rnd, deflate(rnd, level)))
    for level in (1, 6, 9):
        cases.append(("repeat_l%d" % level, "zlib", rep, deflate(rep, level)))
    cases.append(("walk256k_l6", "zlib", walk, deflate(walk, 6)))
    cases.append(("walk64k_l1", "zlib", walk[:65536], deflate(walk[:65536], 1)))
    cases.append(("byte_a", "zlib", b"a", deflate(b"a", 6)))
    big_random = random_bytes(66000, 4)  # two stored blocks (65535 + 465)
    cases.append(("stored_2blocks", "zlib", big_random, deflate(big_random, 0)))
    cases.append(("fixed_text", "zlib", txt, deflate(txt, 6, zlib.Z_FIXED)))
    cases.append(("fixed_repeat", "zlib", rep, deflate(rep, 9, zlib.Z_FIXED)))
    cases.append(("huffman_only", "zlib", txt, deflate(txt, 6, zlib.Z_HUFFMAN_ONLY)))
    cases.append(("rle_walk", "zlib", walk[:32768], deflate(walk[:32768], 6, zlib.Z_RLE)))
    cases.append(("window512_text", "zlib", txt, deflate(txt, 9, wbits=9)))
    # A full flush in the middle: an empty stored block between two compressed runs.
    c = zlib.compressobj(6)
    flushed = c.compress(txt[:7000]) + c.flush(zlib.Z_FULL_FLUSH) + c.compress(txt[7000:]) + c.flush()
    cases.append(("full_flush_text", "zlib", txt, flushed))
    cases.append(("raw_text_l6", "raw", txt, deflate(txt, 6, wbits=-15)))
    cases.append(("raw_random_l9", "raw", rnd, deflate(rnd, 9, wbits=-15)))
    skew = skewed_bytes(300000, 5)
    cases.append(("skewed_l9", "zlib", skew, deflate(skew, 9)))
    cases.append(("skewed_huffman_only", "zlib", skew, deflate(skew, 6, zlib.Z_HUFFMAN_ONLY)))
    with open(os.path.join(out_dir, "manifest.txt"), "w") as m:
        for name, kind, raw, stream in cases:
            # Self-check with the independent implementation before committing anything.
            back = zlib.decompress(stream, -15 if kind == "raw" else 15)
            assert back == raw, name
            with open(os.path.join(out_dir, name + ".zz"), "wb") as f:
                f.write(stream)
            m.write("%s %s %d %08x\n" % (name, kind, len(raw), zlib.crc32(raw) & 0xFFFFFFFF))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "vectors"))
