// Writes the two sample files that check_mat_writer.py parses independently:
//   mat_writer_sample <dir>  ->  <dir>/writer_plain.mat, <dir>/writer_compressed.mat (fixed
//   Huffman), <dir>/writer_stored.mat (stored blocks)
// Content (the Python check hard-codes the same values): acc_z = 0.5 * i - 3 for i = 0..99999
// (100000 x 1), fs = 100, units = "m/s^2".
#include <cstdio>
#include <string>
#include <vector>

#include "imu/mat/mat_writer.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: mat_writer_sample <dir>\n");
    return 2;
  }
  std::vector<double> acc(100000);
  for (std::size_t i = 0; i < acc.size(); ++i) {
    acc[i] = 0.5 * static_cast<double>(i) - 3.0;
  }
  struct Kind {
    const char* file;
    imu::mat::WriterOptions options;
  };
  const Kind kinds[] = {{"/writer_plain.mat", {false, imu::mat::Deflate::fixed_huffman}},
                        {"/writer_compressed.mat", {true, imu::mat::Deflate::fixed_huffman}},
                        {"/writer_stored.mat", {true, imu::mat::Deflate::stored}}};
  for (const Kind& k : kinds) {
    imu::mat::MatWriter w(k.options);
    const std::string path = std::string(argv[1]) + k.file;
    for (const auto& st : {w.add_column("acc_z", acc), w.add_scalar("fs", 100.0),
                           w.add_string("units", "m/s^2"), w.save(path)}) {
      if (!st.ok()) {
        std::fprintf(stderr, "%s\n", st.error().message.c_str());
        return 1;
      }
    }
  }
  return 0;
}
