#!/usr/bin/env python3
"""Print the expected values of test_mat_golden.cpp from the shared data, independently of the
C++ reader: standard library only (struct + zlib, CPython's zlib being an independent inflater).

    python3 tests/mat/golden_values.py ../shared/data/adis16405_imu1.mat

For every double variable: element count, the bit patterns (hex, as uint64) of the first three
and the last sample, and the CRC-32 of all its little-endian data bytes. For char: the text.
Only handles what scipy writes (little-endian, miCOMPRESSED, 2-D double or miUTF8 char).
"""
import struct
import sys
import zlib


def main(path):
    data = open(path, "rb").read()
    assert data[126:128] == b"IM", "little-endian level 5 file expected"
    pos = 128
    while pos < len(data):
        typ, n = struct.unpack_from("<II", data, pos)
        payload = data[pos + 8:pos + 8 + n]
        pos += 8 + n
        if typ != 15:
            continue
        m = zlib.decompress(payload)
        mtyp, mlen = struct.unpack_from("<II", m, 0)
        assert mtyp == 14
        off = 8
        flags_class = struct.unpack_from("<I", m, off + 8)[0]
        off += 16
        _, dbytes = struct.unpack_from("<II", m, off)
        dims = struct.unpack_from("<%di" % (dbytes // 4), m, off + 8)
        off += 8 + dbytes + (-dbytes) % 8
        ntyp, nlen = struct.unpack_from("<II", m, off)
        if ntyp >> 16:  # small data element: size in the upper 16 bits, data in the next 4
            name = m[off + 4:off + 4 + (ntyp >> 16)].decode()
            off += 8
        else:
            name = m[off + 8:off + 8 + nlen].decode()
            off += 8 + nlen + (-nlen) % 8
        rtyp, rlen = struct.unpack_from("<II", m, off)
        raw = m[off + 8:off + 8 + rlen]
        cls = flags_class & 0xFF
        if cls == 6 and rtyp == 9:
            count = rlen // 8
            idx = sorted(set(i for i in (0, 1, 2, count - 1) if 0 <= i < count))
            bits = [struct.unpack_from("<Q", raw, 8 * i)[0] for i in idx]
            vals = [struct.unpack_from("<d", raw, 8 * i)[0] for i in idx]
            print("%s dims=%s count=%d crc32=0x%08x first3+last (index %s) bits=%s values=%s" % (
                name, dims, count, zlib.crc32(raw) & 0xFFFFFFFF, idx,
                ", ".join("0x%016x" % b for b in bits), ", ".join(repr(v) for v in vals)))
        elif cls == 4:
            print("%s dims=%s type=%d text=%r" % (name, dims, rtyp, raw.decode()))


if __name__ == "__main__":
    for p in sys.argv[1:]:
        print("==", p)
        main(p)
