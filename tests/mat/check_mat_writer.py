#!/usr/bin/env python3
"""Independent check of the MAT v5 writer: run mat_writer_sample, then parse its files with the
standard library only (struct + zlib) and compare with the values the sample writes.

    python3 check_mat_writer.py <scratch dir> [emulator args...] <path to mat_writer_sample>

Exit status 0 when the three files (plain, fixed-Huffman compressed, stored) hold exactly acc_z = 0.5 i - 3
(i = 0..99999, 100000 x 1 double), fs = 100 (1 x 1 double) and units = "m/s^2" (1 x 5 char).
"""
import os
import struct
import subprocess
import sys
import zlib


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def sub(buf, off):
    """(type, data bytes, offset of the next tag) of the sub-element at off."""
    w0, w1 = struct.unpack_from("<II", buf, off)
    if w0 >> 16:
        return w0 & 0xFFFF, buf[off + 4:off + 4 + (w0 >> 16)], off + 8
    return w0, buf[off + 8:off + 8 + w1], off + 8 + w1 + (-w1) % 8


def parse(path):
    data = open(path, "rb").read()
    if not data.startswith(b"MATLAB 5.0 MAT-file"):
        fail("%s: header text %r" % (path, data[:20]))
    if data[124:128] != b"\x00\x01IM":
        fail("%s: version/endian bytes %r" % (path, data[124:128]))
    out = {}
    pos = 128
    while pos < len(data):
        typ, n = struct.unpack_from("<II", data, pos)
        payload = data[pos + 8:pos + 8 + n]
        if typ == 15:
            d = zlib.decompressobj()
            m = d.decompress(payload)
            if d.unused_data or not d.eof:
                fail("%s: zlib stream at %d has trailing data or no end" % (path, pos))
            pos += 8 + n
            typ, n = struct.unpack_from("<II", m, 0)
            payload = m[8:8 + n]
            if len(m) != 8 + n:
                fail("%s: inflated %d bytes, element declares %d" % (path, len(m), 8 + n))
        else:
            if n % 8:
                fail("%s: uncompressed element at %d not padded to 8 bytes" % (path, pos))
            pos += 8 + n
        if typ != 14:
            fail("%s: element type %d, not miMATRIX" % (path, typ))
        t, flags, off = sub(payload, 0)
        t2, dims, off = sub(payload, off)
        t3, name, off = sub(payload, off)
        t4, real, off = sub(payload, off)
        if (t, t2, t3) != (6, 5, 1) or off != len(payload):
            fail("%s: sub-element layout %r" % (path, (t, t2, t3, off, len(payload))))
        cls = struct.unpack_from("<I", flags)[0] & 0xFF
        out[name.decode()] = (cls, struct.unpack("<%di" % (len(dims) // 4), dims), t4, real)
    return out


def main(scratch, command):
    os.makedirs(scratch, exist_ok=True)
    subprocess.run(command + [scratch], check=True)
    for f in ("writer_plain.mat", "writer_compressed.mat", "writer_stored.mat"):
        v = parse(os.path.join(scratch, f))
        if sorted(v) != ["acc_z", "fs", "units"]:
            fail("%s: variables %r" % (f, sorted(v)))
        cls, dims, t, real = v["acc_z"]
        want = [0.5 * i - 3.0 for i in range(100000)]
        if cls != 6 or dims != (100000, 1) or t != 9 or list(struct.unpack("<100000d", real)) != want:
            fail("%s: acc_z %r %r %r" % (f, cls, dims, t))
        cls, dims, t, real = v["fs"]
        if cls != 6 or dims != (1, 1) or t != 9 or struct.unpack("<d", real)[0] != 100.0:
            fail("%s: fs" % f)
        cls, dims, t, real = v["units"]
        if cls != 4 or dims != (1, 5) or t != 4 or real.decode("utf-16-le") != "m/s^2":
            fail("%s: units %r %r %r %r" % (f, cls, dims, t, real))
        print("ok: " + f)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
