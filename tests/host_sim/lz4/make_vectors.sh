#!/bin/sh
# Writes the LZ4 vectors test_lz4 decodes, with Debian's lz4 command line tool (lz4 1.9.4), an
# implementation independent of imu-sim's decoder. Run once in this folder; the outputs are
# committed:
#   lines.txt      105000 bytes of text lines (the expected content)
#   lines.lz4      lz4 -B4 -BD --content-size: 64 KiB blocks, linked (a match reaches into the
#                  block before), the content size and the content checksum in the frame
#   lines_bx.lz4   lz4 -B4 -BX --no-frame-crc: independent blocks, each with a block checksum
#   random.bin     1000 pseudo-random bytes (Python's random.Random(7); the expected content)
#   random.lz4     lz4: one block stored uncompressed (high bit of its size word)
set -eu
awk 'BEGIN { for (i = 0; i < 3000; ++i) printf "%05d,imu_link,%d,0.000000,9.806650\n", i, i % 7 }' > lines.txt
lz4 -q -f -B4 -BD --content-size lines.txt lines.lz4
lz4 -q -f -B4 -BX --no-frame-crc lines.txt lines_bx.lz4
python3 -c 'import random, sys; r = random.Random(7)
sys.stdout.buffer.write(bytes(r.getrandbits(8) for _ in range(1000)))' > random.bin
lz4 -q -f random.bin random.lz4
