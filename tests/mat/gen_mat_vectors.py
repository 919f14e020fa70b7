#!/usr/bin/env python3
"""Generate the MAT-file test vectors of test_mat_reader.cpp. Run once; the outputs are committed:

    /usr/bin/python3 tests/mat/gen_mat_vectors.py tests/mat/vectors   # needs python3-scipy

scipy_v5_compressed.mat / scipy_v5_uncompressed.mat: written by scipy.io.savemat (an independent
MAT v5 writer), same variables, with and without miCOMPRESSED. scipy_v4.mat: a level 4 file
(must be rejected). handmade_be.mat / handmade_mixed.mat: built byte by byte below with struct
(big-endian "MI" file; class double stored as miUINT8 and int16 in a small data element, the
way MATLAB stores integer-valued doubles). The expected values in the C++ test are the inputs
written here.
"""
import os
import struct
import sys

import numpy as np
import scipy.io


def variables():
    cell = np.empty((1, 2), dtype=object)
    cell[0, 0] = np.array([[1.0]])
    cell[0, 1] = "x"
    return {
        # Order matters: the skipped classes come first, the reader must step over them.
        "cellvar": cell,
        "structvar": {"a": np.array([[1.0, 2.0]]), "b": "text"},
        "d_col": np.array([[1.5], [-2.25], [3e10], [-0.0], [1e-300]]),
        "d_row": np.array([[1.0, 2.0, 3.0, 4.5]]),
        "d_mat": np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]]),
        "s_col": np.array([[0.5], [-1.25], [3.0]], dtype=np.float32),
        "i8": np.array([[-128], [0], [127]], dtype=np.int8),
        "u8": np.array([[0], [255]], dtype=np.uint8),
        "i16": np.array([[-32768], [32767]], dtype=np.int16),
        "u16": np.array([[65535]], dtype=np.uint16),
        "i32": np.array([[-2147483648], [2147483647]], dtype=np.int32),
        "u32": np.array([[4294967295]], dtype=np.uint32),
        "i64": np.array([[-9007199254740992], [123456789]], dtype=np.int64),
        "u64": np.array([[9007199254740992]], dtype=np.uint64),
        "flag": np.array([[True], [False], [True]]),
        "scalar": 42.0,
        "text": "hello MAT",
        "charmat": np.array(["ab", "cd"]),
        "cplx": np.array([[1.0 + 2.0j]]),
        "empty": np.zeros((0, 0)),
        "cube": np.arange(24.0).reshape((2, 3, 4), order="F"),
    }


def tag(t, n, be=False):
    return struct.pack(">II" if be else "<II", t, n)


def pad8(b):
    return b + b"\0" * ((8 - len(b) % 8) % 8)


def header(be=False):
    text = b"MATLAB 5.0 MAT-file, handmade by gen_mat_vectors.py".ljust(116, b" ")
    return text + b"\0" * 8 + (b"\x01\x00MI" if be else b"\x00\x01IM")


def matrix(cls, dims, name, data_type, data, be=False):
    e = ">" if be else "<"
    body = tag(6, 8, be) + struct.pack(e + "II", cls, 0)
    body += tag(5, 4 * len(dims), be) + pad8(struct.pack(e + "%di" % len(dims), *dims))
    body += tag(1, len(name), be) + pad8(name)
    if len(data) <= 4:  # small data element: 16-bit size, 16-bit type, then the data
        body += struct.pack(e + "I", (len(data) << 16) | data_type) + data.ljust(4, b"\0")
    else:
        body += tag(data_type, len(data), be) + pad8(data)
    return tag(14, len(body), be) + body


def main(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    v = variables()
    scipy.io.savemat(os.path.join(out_dir, "scipy_v5_compressed.mat"), v, do_compression=True)
    scipy.io.savemat(os.path.join(out_dir, "scipy_v5_uncompressed.mat"), v, do_compression=False)
    scipy.io.savemat(os.path.join(out_dir, "scipy_v4.mat"), {"d_col": v["d_col"]}, format="4")

    be = header(True)
    be += matrix(6, [2, 1], b"be_col", 9, struct.pack(">2d", 1.0, -2.5), True)
    be += matrix(4, [1, 2], b"be_text", 4, struct.pack(">2H", ord("h"), ord("i")), True)
    be += matrix(12, [3, 1], b"be_i32", 5, struct.pack(">3i", -7, 0, 2000000000), True)
    with open(os.path.join(out_dir, "handmade_be.mat"), "wb") as f:
        f.write(be)

    mixed = header()
    mixed += matrix(6, [3, 1], b"d_as_u8", 2, bytes([1, 2, 250]))  # small element, 3 bytes
    mixed += matrix(6, [1, 2], b"d_as_i16", 3, struct.pack("<2h", -300, 301))  # small element
    mixed += matrix(6, [1, 1], b"d_as_u8_1", 2, bytes([9]))
    with open(os.path.join(out_dir, "handmade_mixed.mat"), "wb") as f:
        f.write(mixed)

    # Independent read-back check of what was written.
    back = scipy.io.loadmat(os.path.join(out_dir, "scipy_v5_compressed.mat"))
    assert np.array_equal(back["d_mat"], v["d_mat"])


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "vectors"))
