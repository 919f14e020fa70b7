% Writes the GNU Octave fixtures of tests/host_sim/test_octave_files.cpp (real
% clients over our own fixtures). Run once, from this folder, with Debian's octave:
%   octave-cli --no-gui make_fixtures.m
% and commit the .mat files and octave_ref.txt it writes (CI does not install Octave).
% The data: 2000 samples at 100 Hz of white noise on an int16 count lattice (LSB 0.01 m/s^2).
% octave_ref.txt holds the fully overlapping Allan deviation of acc_z at m = 1, 2, 4, 8 samples,
% computed here independently of the product (at these m the product's estimator is the fully
% overlapping one).
randn("state", 20261122);
n = 2000;
fs = 100;
acc_lsb = 0.01;
counts = int16(round(40 * randn(n, 1)));
acc_z = double(counts) * acc_lsb;
acc_x = double(int16(round(30 * randn(n, 1)))) * acc_lsb;
save("-v6", "octave_v6.mat", "acc_z", "fs", "acc_lsb");
save("-v7", "octave_v7.mat", "acc_z", "fs", "acc_lsb");
row = acc_z';
acc_z_row = row;
save("-v7", "octave_row.mat", "acc_z_row", "fs", "acc_lsb");
acc_z_counts = counts;
save("-v7", "octave_int16.mat", "acc_z_counts", "fs", "acc_lsb");
data = [acc_x, acc_z, 2 * acc_z];
save("-v7", "octave_matrix.mat", "data", "fs", "acc_lsb");
imu.acc_x = acc_x;
imu.acc_z = acc_z;
imu.fs = fs;
save("-v7", "octave_struct.mat", "imu", "acc_lsb");
rec.note = "nested struct, uncompressed";
rec.imu = imu;
save("-v6", "octave_struct_v6.mat", "rec", "acc_lsb");
Fs = fs;
save("-v6", "octave_capital_fs.mat", "acc_z", "Fs", "acc_lsb");
f = fopen("octave_ref.txt", "w");
fprintf(f, "# tau_s oadev (fully overlapping, acc_z of the fixtures, Octave %s)\n", version());
x = cumsum([0; acc_z]);
for m = [1, 2, 4, 8]
  d = x(1 + 2 * m:end) - 2 * x(1 + m:end - m) + x(1:end - 2 * m);
  av = sum(d .^ 2) / (2 * m ^ 2 * (n - 2 * m + 1));
  fprintf(f, "%.17g %.17g\n", m / fs, sqrt(av));
end
fclose(f);
