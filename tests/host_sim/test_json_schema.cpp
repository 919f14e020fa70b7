// Every command's JSON against host_sim/cli/imu-sim.schema.json: adev (exact and online, one
// channel and several, MAT and text), analyze (one channel and several) and run. The schema is
// read by a small JSON parser and checked by a validator of the JSON Schema keywords it uses
// (a keyword the validator does not know fails the test, so no constraint is silently skipped).
// Besides the schema: every key is snake_case (the channels' own names excepted).
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "imu/mat/mat_writer.hpp"
#include "sim_test_util.hpp"

namespace {

// ---- a JSON value and its parser (RFC 8259; enough for our documents) ----------------------

struct Value {
  enum class Kind { kNull, kBool, kNumber, kString, kArray, kObject } kind = Kind::kNull;
  bool b = false;
  double num = 0.0;
  bool integer = false;  // written without a fraction or exponent
  std::string str;
  std::vector<Value> arr;
  std::vector<std::pair<std::string, Value>> obj;  // in document order
  [[nodiscard]] const Value* get(const std::string& key) const {
    for (const auto& kv : obj) {
      if (kv.first == key) {
        return &kv.second;
      }
    }
    return nullptr;
  }
};

class Parser {
 public:
  explicit Parser(const std::string& text) : s_(text) {}
  bool parse(Value& out, std::string& err) {
    if (!value(out) || (skip(), pos_ != s_.size())) {
      err = "JSON parse error at byte " + std::to_string(pos_);
      return false;
    }
    return true;
  }

 private:
  void skip() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_])) != 0) {
      ++pos_;
    }
  }
  bool literal(const char* word) {
    const std::string w(word);
    if (s_.compare(pos_, w.size(), w) != 0) {
      return false;
    }
    pos_ += w.size();
    return true;
  }
  bool string(std::string& out) {
    if (pos_ >= s_.size() || s_[pos_] != '"') {
      return false;
    }
    ++pos_;
    while (pos_ < s_.size() && s_[pos_] != '"') {
      if (s_[pos_] == '\\') {
        if (++pos_ >= s_.size()) {
          return false;
        }
        const char e = s_[pos_];
        if (e == 'u') {
          pos_ += 4;  // kept as a placeholder: names are compared only when ASCII
          out += '?';
        } else {
          out += e == 'n' ? '\n' : e == 't' ? '\t' : e == 'r' ? '\r' : e == 'b' ? '\b'
                 : e == 'f' ? '\f' : e;
        }
        ++pos_;
      } else {
        out += s_[pos_++];
      }
    }
    if (pos_ >= s_.size()) {
      return false;
    }
    ++pos_;
    return true;
  }
  bool value(Value& v) {
    skip();
    if (pos_ >= s_.size()) {
      return false;
    }
    const char c = s_[pos_];
    if (c == '{') {
      ++pos_;
      v.kind = Value::Kind::kObject;
      skip();
      if (pos_ < s_.size() && s_[pos_] == '}') {
        ++pos_;
        return true;
      }
      for (;;) {
        skip();
        std::string key;
        if (!string(key)) {
          return false;
        }
        skip();
        if (pos_ >= s_.size() || s_[pos_++] != ':') {
          return false;
        }
        Value m;
        if (!value(m)) {
          return false;
        }
        v.obj.emplace_back(std::move(key), std::move(m));
        skip();
        if (pos_ < s_.size() && s_[pos_] == ',') {
          ++pos_;
          continue;
        }
        return pos_ < s_.size() && s_[pos_++] == '}';
      }
    }
    if (c == '[') {
      ++pos_;
      v.kind = Value::Kind::kArray;
      skip();
      if (pos_ < s_.size() && s_[pos_] == ']') {
        ++pos_;
        return true;
      }
      for (;;) {
        Value m;
        if (!value(m)) {
          return false;
        }
        v.arr.push_back(std::move(m));
        skip();
        if (pos_ < s_.size() && s_[pos_] == ',') {
          ++pos_;
          continue;
        }
        return pos_ < s_.size() && s_[pos_++] == ']';
      }
    }
    if (c == '"') {
      v.kind = Value::Kind::kString;
      return string(v.str);
    }
    if (literal("true") || literal("false")) {
      v.kind = Value::Kind::kBool;
      v.b = s_[pos_ - 1] == 'e' && s_[pos_ - 2] == 'u';
      return true;
    }
    if (literal("null")) {
      return true;
    }
    const char* start = s_.c_str() + pos_;
    char* end = nullptr;
    v.num = std::strtod(start, &end);
    if (end == start) {
      return false;
    }
    const std::string text(start, static_cast<std::size_t>(end - start));
    v.kind = Value::Kind::kNumber;
    v.integer = text.find_first_of(".eE") == std::string::npos;
    pos_ += text.size();
    return true;
  }
  const std::string& s_;
  std::size_t pos_ = 0;
};

// ---- the validator: the JSON Schema 2020-12 keywords the schema uses -------------------------

const std::set<std::string> kKnownKeywords = {
    "$schema", "$id",   "title", "description", "type",      "const",         "enum",
    "required", "properties", "additionalProperties", "items", "minProperties", "minimum",
    "exclusiveMinimum", "$ref", "$defs", "allOf", "if", "then"};

class Validator {
 public:
  explicit Validator(const Value& root) : root_(root) {}
  // Errors of `doc` against schema `s` at `path` (appended to errors_).
  void check(const Value& doc, const Value& s, const std::string& path) {
    for (const auto& kv : s.obj) {
      if (kKnownKeywords.count(kv.first) == 0) {
        errors_.push_back(path + ": schema keyword '" + kv.first + "' is not checked");
      }
    }
    if (const Value* ref = s.get("$ref")) {
      const std::string prefix = "#/$defs/";
      const Value* defs = root_.get("$defs");
      const Value* target = ref->str.rfind(prefix, 0) == 0 && defs != nullptr
                                ? defs->get(ref->str.substr(prefix.size()))
                                : nullptr;
      if (target == nullptr) {
        errors_.push_back(path + ": unresolved $ref " + ref->str);
        return;
      }
      check(doc, *target, path);
    }
    if (const Value* t = s.get("type")) {
      bool ok = false;
      if (t->kind == Value::Kind::kString) {
        ok = is_type(doc, t->str);
      }
      for (const Value& one : t->arr) {
        ok = ok || is_type(doc, one.str);
      }
      if (!ok) {
        errors_.push_back(path + ": wrong type");
        return;
      }
    }
    if (const Value* c = s.get("const")) {
      if (!equal(doc, *c)) {
        errors_.push_back(path + ": not the constant the schema names");
      }
    }
    if (const Value* e = s.get("enum")) {
      bool found = false;
      for (const Value& one : e->arr) {
        found = found || equal(doc, one);
      }
      if (!found) {
        errors_.push_back(path + ": '" + doc.str + "' not in the enum");
      }
    }
    if (doc.kind == Value::Kind::kNumber) {
      if (const Value* m = s.get("minimum"); m != nullptr && doc.num < m->num) {
        errors_.push_back(path + ": below the minimum");
      }
      if (const Value* m = s.get("exclusiveMinimum"); m != nullptr && !(doc.num > m->num)) {
        errors_.push_back(path + ": not above the exclusive minimum");
      }
    }
    if (doc.kind == Value::Kind::kObject) {
      check_object(doc, s, path);
    }
    if (const Value* items = s.get("items"); items != nullptr && doc.kind == Value::Kind::kArray) {
      for (std::size_t i = 0; i < doc.arr.size(); ++i) {
        check(doc.arr[i], *items, path + "[" + std::to_string(i) + "]");
      }
    }
    if (const Value* all = s.get("allOf")) {
      for (const Value& sub : all->arr) {
        const Value* cond = sub.get("if");
        if (cond != nullptr) {
          Validator probe(root_);
          probe.check(doc, *cond, path);
          if (probe.errors_.empty() && sub.get("then") != nullptr) {
            check(doc, *sub.get("then"), path);
          }
        } else {
          check(doc, sub, path);
        }
      }
    }
  }
  [[nodiscard]] const std::vector<std::string>& errors() const { return errors_; }

 private:
  void check_object(const Value& doc, const Value& s, const std::string& path) {
    if (const Value* req = s.get("required")) {
      for (const Value& k : req->arr) {
        if (doc.get(k.str) == nullptr) {
          errors_.push_back(path + ": missing required key '" + k.str + "'");
        }
      }
    }
    if (const Value* m = s.get("minProperties");
        m != nullptr && static_cast<double>(doc.obj.size()) < m->num) {
      errors_.push_back(path + ": fewer members than minProperties");
    }
    const Value* props = s.get("properties");
    const Value* extra = s.get("additionalProperties");
    for (const auto& kv : doc.obj) {
      const Value* sub = props != nullptr ? props->get(kv.first) : nullptr;
      if (sub != nullptr) {
        check(kv.second, *sub, path + "." + kv.first);
      } else if (extra != nullptr && extra->kind == Value::Kind::kBool && !extra->b) {
        errors_.push_back(path + ": key '" + kv.first + "' is not in the schema");
      } else if (extra != nullptr && extra->kind == Value::Kind::kObject) {
        check(kv.second, *extra, path + "." + kv.first);
      }
    }
  }
  static bool is_type(const Value& v, const std::string& t) {
    using K = Value::Kind;
    return (t == "object" && v.kind == K::kObject) || (t == "array" && v.kind == K::kArray) ||
           (t == "string" && v.kind == K::kString) || (t == "boolean" && v.kind == K::kBool) ||
           (t == "null" && v.kind == K::kNull) || (t == "number" && v.kind == K::kNumber) ||
           (t == "integer" && v.kind == K::kNumber && v.integer);
  }
  static bool equal(const Value& a, const Value& b) {
    if (a.kind != b.kind) {
      return false;
    }
    switch (a.kind) {
      case Value::Kind::kNumber: return !(a.num < b.num || a.num > b.num);
      case Value::Kind::kString: return a.str == b.str;
      case Value::Kind::kBool: return a.b == b.b;
      case Value::Kind::kNull: return true;
      default: return false;
    }
  }
  const Value& root_;
  std::vector<std::string> errors_;
};

// Keys that are not snake_case ([a-z][a-z0-9_]*), the channels' names (the keys of the top
// level "channels") excepted.
void snake_case_violations(const Value& v, const std::string& path, bool names_here,
                           std::vector<std::string>& out) {
  for (const auto& kv : v.obj) {
    bool ok = !kv.first.empty() && std::islower(static_cast<unsigned char>(kv.first[0])) != 0;
    for (const char c : kv.first) {
      ok = ok && (std::islower(static_cast<unsigned char>(c)) != 0 ||
                  std::isdigit(static_cast<unsigned char>(c)) != 0 || c == '_');
    }
    if (!ok && !names_here) {
      out.push_back(path + "." + kv.first);
    }
    snake_case_violations(kv.second, path + "." + kv.first, path.empty() && kv.first == "channels",
                          out);
  }
  for (const Value& a : v.arr) {
    snake_case_violations(a, path + "[]", false, out);
  }
}

Value load(const std::string& text) {
  Value v;
  std::string err;
  Parser p(text);
  EXPECT_TRUE(p.parse(v, err)) << err << "\n" << text.substr(0, 400);
  return v;
}

std::vector<std::string> problems(const Value& schema, const std::string& json) {
  const Value doc = load(json);
  Validator val(schema);
  val.check(doc, schema, "$");
  std::vector<std::string> out = val.errors();
  snake_case_violations(doc, "", false, out);
  return out;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) {
    s += x + "\n";
  }
  return s;
}

// A small two-sensor record: a MAT-file and the same samples as a CSV with a time column.
void write_inputs(const std::string& mat, const std::string& csv) {
  constexpr std::size_t kN = 20000;
  std::vector<double> acc(kN);
  std::vector<double> gyro(kN);
  std::uint64_t x = 88172645463325252ULL;
  for (std::size_t i = 0; i < kN; ++i) {
    x ^= x << 13U;
    x ^= x >> 7U;
    x ^= x << 17U;
    acc[i] = 9.81 + 1e-4 * static_cast<double>(static_cast<std::int64_t>(x % 2001) - 1000);
    gyro[i] = 1e-5 * static_cast<double>(static_cast<std::int64_t>((x >> 20U) % 2001) - 1000);
  }
  imu::mat::MatWriter w;
  ASSERT_TRUE(w.add_column("acc_z", acc).ok());
  ASSERT_TRUE(w.add_column("gyro_x", gyro).ok());
  ASSERT_TRUE(w.add_scalar("fs", 100.0).ok());
  ASSERT_TRUE(w.add_scalar("acc_lsb", 1e-4).ok());
  ASSERT_TRUE(w.add_scalar("gyro_lsb", 1e-5).ok());
  {
    std::ofstream f(mat, std::ios::binary);
    f.write(reinterpret_cast<const char*>(w.bytes().data()),
            static_cast<std::streamsize>(w.bytes().size()));
  }
  std::ofstream f(csv);
  f << "t,acc_z,gyro_x\n";
  char buf[96];
  for (std::size_t i = 0; i < kN; ++i) {
    std::snprintf(buf, sizeof buf, "%.2f,%.4f,%.5f\n", static_cast<double>(i) / 100.0, acc[i],
                  gyro[i]);
    f << buf;
  }
}

}  // namespace

TEST(JsonSchema, EveryCommandsJsonFollowsTheSchemaForOneChannelAndMany) {
  const Value schema = load(simtest::read_text(IMU_JSON_SCHEMA));
  ASSERT_EQ(schema.kind, Value::Kind::kObject);
  simtest::TempDir dir;
  const std::string mat = dir.file("rec.mat");
  const std::string csv = dir.file("rec.csv");
  write_inputs(mat, csv);
  struct Case {
    std::vector<std::string> args;
    std::string json;
  };
  std::vector<Case> cases = {
      {{"adev", mat, "--channel", "acc_z"}, dir.file("adev1.json")},
      {{"adev", mat, "--channel", "acc_z,gyro_x"}, dir.file("adev2.json")},
      {{"adev", mat, "--channel", "gyro_x", "--estimator", "online"}, dir.file("adev_on.json")},
      {{"adev", mat, "--channel", "acc_z", "--deviation", "adev,mdev,hdev,tdev"},
       dir.file("adev_devs.json")},
      {{"adev", csv, "--channel", "acc_z,gyro_x"}, dir.file("adev_csv.json")},
      {{"analyze", mat, "--channel", "acc_z"}, dir.file("an1.json")},
      {{"analyze", csv, "--channel", "acc_z,gyro_x"}, dir.file("an2.json")},
  };
  for (Case& c : cases) {
    c.args.insert(c.args.end(), {"--json", c.json});
  }
  // run: the first channel through the in-process node on the loopback bus (a thread: not
  // under qemu-user, where a second thread hangs; the native and VM runs cover it).
#ifndef IMU_EMULATED_TARGET
  cases.push_back({{"run", mat, "--channel", "acc_z", "--no-plots", "--quiet", "--sim-windows", "5",
                    "--out", dir.file("run")},
                   dir.file("run") + "/report.json"});
#endif
  std::set<std::string> commands;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args[0] + " " + c.args[2] + " " + c.args[3]);
    const auto r = simtest::run(c.args);
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string json = simtest::read_text(c.json);
    EXPECT_EQ(joined(problems(schema, json)), "");
    const Value doc = load(json);
    const Value* command = doc.get("command");
    const Value* channels = doc.get("channels");
    if (command == nullptr || channels == nullptr) {
      ADD_FAILURE() << "no command or channels";
      continue;
    }
    commands.insert(command->str);
    // One shape for one channel or many: the channels are always a map of name to object.
    EXPECT_EQ(channels->obj.size(), c.args[3].find(',') == std::string::npos ? 1U : 2U);
  }
#ifndef IMU_EMULATED_TARGET
  EXPECT_EQ(commands, (std::set<std::string>{"adev", "analyze", "run"}));
#endif
}

// The validator itself: documents the schema must refuse are refused (a test that cannot fail
// would prove nothing).
TEST(JsonSchema, TheValidatorRefusesWhatTheSchemaForbids) {
  const Value schema = load(simtest::read_text(IMU_JSON_SCHEMA));
  const std::string channel =
      R"({"channel": "acc_z", "unit": "m/s^2", "fs_hz": 100, "lsb": 1e-4, "n_samples": 10,
          "adev": [{"tau_s": 0.01, "adev": 1e-3, "edf": 5, "ci_lo": 9e-4, "ci_hi": 1.1e-3,
                    "n_terms": 8, "af": 1}],
          "units": {"n": "a", "q": "a", "b": "a", "k": "a", "r": "a", "sb": "a", "tb_s": "s",
                    "sigma": "a", "amplitude": "a", "size": "a", "adev": "a"}})";
  const std::string good = R"({"schema_version": 1, "command": "analyze", "source": "f.mat",
                               "channels": {"acc_z": )" + channel + "}}";
  EXPECT_EQ(joined(problems(schema, good)), "");
  const auto refused = [&](const std::string& from, const std::string& to) {
    std::string bad = good;
    const std::size_t at = bad.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    bad.replace(at, from.size(), to);
    return !problems(schema, bad).empty();
  };
  EXPECT_TRUE(refused(R"("schema_version": 1)", R"("schema_version": 2)"));
  EXPECT_TRUE(refused(R"("command": "analyze")", R"("command": "adev")"));  // no estimator
  EXPECT_TRUE(refused(R"("source": "f.mat",)", R"("file": "f.mat",)"));
  EXPECT_TRUE(refused(R"("fs_hz": 100)", R"("fs_hz": 0)"));
  EXPECT_TRUE(refused(R"("n_terms": 8)", R"("n_terms": 8.5)"));
  EXPECT_TRUE(refused(R"("unit": "m/s^2",)", R"("unit": "m/s^2", "cpuSeconds": 1,)"));
  EXPECT_TRUE(refused(R"("channels": {"acc_z": )", R"("channels": {}, "x": {"acc_z": )"));
}
