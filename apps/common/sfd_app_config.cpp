// SPDX-License-Identifier: MIT
#include "sfd_app_config.hpp"
#include "sfd_opencv_quiet.hpp"

#include <opencv2/core.hpp>
#include <sys/stat.h>

#include <cctype>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace sfdapp {

AppConfig::AppConfig() {
    sfd_node_config_default(&node);
}

std::string AppConfig::origin_of(const std::string &key) const {
    const auto it = origin.find(key.substr(0, key.find('[')));
    return it == origin.end() ? std::string("default") : it->second;
}

namespace {

// The method names in sfd_method_t order (SFD_METHOD_NONE = 0 ... SFD_METHOD_BOTH = 5).
constexpr const char *kMethods[] = {"none", "parity", "oprf", "ransac1", "ransacf", "both"};
constexpr int kNumMethods = static_cast<int>(sizeof kMethods / sizeof kMethods[0]);
const char *const kMethodList = "none, parity, oprf, ransac1, ransacf, both";

// Largest |value| of a microsecond key (an int64 with room to add two of them).
constexpr double kMaxMicros = 9.0e15;

std::string quoted(const std::string &s) {
    // A message is one line: control characters (a YAML "\n" escape gives a real line break)
    // are written as escapes.
    std::string q = "\"";
    for (const char c : s) {
        const unsigned char u = static_cast<unsigned char>(c);
        if (c == '\n') {
            q += "\\n";
        } else if (c == '\r') {
            q += "\\r";
        } else if (c == '\t') {
            q += "\\t";
        } else if (u < 0x20 || u == 0x7f) {
            static const char kHex[] = "0123456789abcdef";
            q += "\\x";
            q += kHex[u >> 4];
            q += kHex[u & 15u];
        } else {
            q += c;
        }
    }
    return q + "\"";
}

}  // namespace

std::string format_double(double v, bool mark_real) {
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char buf[40];
    if (v == std::floor(v) && std::fabs(v) < 1e16) {
        std::snprintf(buf, sizeof buf, mark_real ? "%.1f" : "%.0f", v);
        return buf;
    }
    for (int prec = 1; prec <= 17; ++prec) {
        std::snprintf(buf, sizeof buf, "%.*g", prec, v);
        if (std::strtod(buf, nullptr) == v) break;
    }
    std::string s(buf);
    if (mark_real && s.find_first_of(".e") == std::string::npos) s += ".0";
    return s;
}

bool set_method(const std::string &name, AppConfig *cfg, std::string *error) {
    for (int m = 0; m < kNumMethods; ++m) {
        if (name == kMethods[m]) {
            cfg->node.params.method = m;
            cfg->method = name;
            return true;
        }
    }
    *error = std::string("not one of ") + kMethodList;
    return false;
}

namespace {

// ---- the file's integer literals -------------------------------------------------------------

std::string trim(const std::string &s) {
    const size_t b = s.find_first_not_of(" \t\r");
    if (b == std::string::npos) return "";
    const size_t e = s.find_last_not_of(" \t\r");
    return s.substr(b, e - b + 1);
}

// The line without its comment ('#' at the start or after a blank, outside quotes).
std::string strip_comment(const std::string &line) {
    char quote = 0;
    for (size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        if (quote != 0) {
            if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
            quote = c;
        } else if (c == '#' && (i == 0 || line[i - 1] == ' ' || line[i - 1] == '\t')) {
            return line.substr(0, i);
        }
    }
    return line;
}

// Position of the ':' that ends a mapping key (followed by a blank or the end), outside quotes.
size_t key_colon(const std::string &s) {
    char quote = 0;
    for (size_t i = 0; i < s.size(); ++i) {
        const char c = s[i];
        if (quote != 0) {
            if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
            quote = c;
        } else if (c == ':' && (i + 1 == s.size() || s[i + 1] == ' ' || s[i + 1] == '\t')) {
            return i;
        } else if (c == '[' || c == '{') {
            return std::string::npos;  // a flow collection, not a key
        }
    }
    return std::string::npos;
}

bool is_digit(char c) {
    return std::isdigit(static_cast<unsigned char>(c)) != 0;
}

// One plain scalar. cv::FileStorage reads an integer literal with (int)strtol(text, 0, 0): a value
// beyond 32 bits wraps silently (123456789012 -> -1097262572, 4294967297 -> 1), a leading 0 is
// octal (010 -> 8) and 0x hexadecimal. Such literals are refused here, before they are read.
bool check_literal(const std::string &tok, const std::string &where, std::string *error) {
    size_t i = (!tok.empty() && (tok[0] == '+' || tok[0] == '-')) ? 1 : 0;
    if (i >= tok.size() || !is_digit(tok[i])) return true;  // not a number literal
    size_t j = i;
    while (j < tok.size() && is_digit(tok[j])) ++j;
    if (j < tok.size()) {
        const char c = tok[j];
        if (c == '.' || c == 'e' || c == 'E') return true;  // a real: strtod
        if (tok[i] == '0') {
            *error = where + ": " + tok + " is not a decimal number";
            return false;
        }
        return true;  // cv::FileStorage's own error
    }
    if (j - i > 1 && tok[i] == '0') {
        *error = where + ": " + tok + " has a leading 0 (cv::FileStorage would read it as octal)";
        return false;
    }
    errno = 0;
    const long long v = std::strtoll(tok.c_str(), nullptr, 10);
    if (errno == ERANGE || v < std::numeric_limits<int32_t>::min() ||
        v > std::numeric_limits<int32_t>::max()) {
        *error = where + ": " + tok + " is outside the 32-bit integer range";
        return false;
    }
    return true;
}

// A scalar's text (quoted strings and nested collections are not number literals).
bool check_scalar(const std::string &text, const std::string &where, std::string *error) {
    const std::string v = trim(text);
    if (v.empty() || v[0] == '"' || v[0] == '\'' || v[0] == '[' || v[0] == '{') return true;
    return check_literal(v, where, error);
}

// The value text of `key` (after "key:" or "- "): a scalar, or a flow list or map of scalars.
bool check_value(const std::string &value, const std::string &key, const std::string &path,
                 std::string *error) {
    const std::string v = trim(value);
    if (v.empty() || (v[0] != '[' && v[0] != '{')) return check_scalar(v, path + ": " + key, error);
    const bool map = v[0] == '{';
    std::string inner = v.substr(1);
    const size_t close = inner.find_last_of(map ? '}' : ']');
    if (close != std::string::npos) inner.resize(close);
    std::stringstream ss(inner);
    std::string item;
    int k = 0;
    while (std::getline(ss, item, ',')) {
        std::string sub = key + "[" + std::to_string(k++) + "]";
        std::string text = trim(item);
        if (map) {
            const size_t c = key_colon(text);
            if (c == std::string::npos) continue;
            sub = key + "." + trim(text.substr(0, c));
            text = text.substr(c + 1);
        }
        std::string where = path;
        where.append(": ").append(sub);
        if (!check_scalar(text, where, error)) return false;
    }
    return true;
}

// Scans the text of the file for the integer literals cv::FileStorage would misread (see
// check_literal), naming the key: "PATH: filter.window_size: 010 has a leading 0 ...". Keys are
// tracked by indentation (a top-level key and the keys under it, as in apps/config/sfd.yaml).
bool check_integer_literals(const std::string &path, std::string *error) {
    std::ifstream in(path);
    std::string line, top, last;
    while (std::getline(in, line)) {
        const std::string s = strip_comment(line);
        const size_t indent = s.find_first_not_of(" \t");
        if (indent == std::string::npos) continue;
        std::string body = trim(s.substr(indent));
        if (body.empty() || body[0] == '%' || body.rfind("---", 0) == 0 ||
            body.rfind("...", 0) == 0) {
            continue;
        }
        std::string key = last;
        if (body[0] == '-' && (body.size() == 1 || body[1] == ' ')) {
            body = body.substr(1);  // an element of a block list: of the last key
        } else {
            const size_t c = key_colon(body);
            if (c == std::string::npos) {
                if (!check_value(body, last, path, error)) return false;  // a continued value
                continue;
            }
            key = trim(body.substr(0, c));
            if (key.size() >= 2 && (key[0] == '"' || key[0] == '\'')) {
                key = key.substr(1, key.size() - 2);
            }
            if (indent == 0) {
                top = key;
            } else if (!top.empty()) {
                key.insert(0, ".").insert(0, top);
            }
            last = key;
            body = body.substr(c + 1);
        }
        if (!check_value(body, key, path, error)) return false;
    }
    return true;
}

// ---- reading the keys ---------------------------------------------------------------------------

// A scalar node's value as the error messages show it.
std::string describe_scalar(const cv::FileNode &n) {
    if (n.isInt()) return std::to_string(static_cast<int>(n));
    if (n.isReal()) return format_double(static_cast<double>(n), true);
    if (n.isString()) return quoted(static_cast<std::string>(n));
    if (n.isSeq()) return "a list";
    if (n.isMap()) return "a map";
    return "an empty value";
}

// A node's value as the error messages show it (a list with its first elements).
std::string describe(const cv::FileNode &n) {
    if (!n.isSeq()) return describe_scalar(n);
    std::string s = "[";
    for (size_t k = 0; k < n.size(); ++k) {
        if (k > 0) s += ", ";
        if (k == 8) {
            s += "...";
            break;
        }
        s += describe_scalar(n[static_cast<int>(k)]);
    }
    return s + "]";
}

// Reads keys of the file at `path` into `cfg`, recording `path` as their origin; the first
// failure sets "PATH: KEY: VALUE is not ..." and returns false.
class Reader {
  public:
    Reader(const std::string &path, AppConfig *cfg, std::string *error)
        : path_(path), cfg_(cfg), error_(error) {}

    bool fail(const std::string &key, const cv::FileNode &n, const std::string &why) {
        *error_ = path_ + ": " + key + ": " + describe(n) + " " + why;
        return false;
    }
    bool fail_text(const std::string &key, const std::string &why) {
        *error_ = path_ + ": " + key + ": " + why;
        return false;
    }
    void set(const std::string &key) { cfg_->origin[key.substr(0, key.find('['))] = path_; }

    bool number(const cv::FileNode &n, const std::string &key, double *out) {
        if (!n.isReal() && !n.isInt()) return fail(key, n, "is not a number");
        *out = static_cast<double>(n);
        set(key);
        return true;
    }
    template <typename Int>
    bool integer(const cv::FileNode &n, const std::string &key, Int *out) {
        if (!n.isInt()) return fail(key, n, "is not an integer");
        *out = static_cast<Int>(static_cast<int>(n));
        set(key);
        return true;
    }
    bool string(const cv::FileNode &n, const std::string &key, std::string *out) {
        if (!n.isString()) return fail(key, n, "is not a string");
        *out = static_cast<std::string>(n);
        set(key);
        return true;
    }
    // Microseconds: an integer, or a real with a whole value (5e9 is beyond 32-bit integers).
    bool micros(const cv::FileNode &n, const std::string &key, int64_t *out) {
        double d = 0.0;
        if (!number(n, key, &d)) return false;
        if (!std::isfinite(d) || d != std::floor(d)) {
            return fail(key, n, "is not a whole number of microseconds");
        }
        if (!(std::fabs(d) <= kMaxMicros)) return fail(key, n, "is beyond 9e15 microseconds");
        *out = static_cast<int64_t>(d);
        return true;
    }
    bool vec3(const cv::FileNode &n, const std::string &key, double out[3]) {
        if (!n.isSeq() || n.size() != 3) return fail(key, n, "is not a list of 3 numbers");
        double v[3];
        for (int k = 0; k < 3; ++k) {
            if (!number(n[k], key + "[" + std::to_string(k) + "]", &v[k])) return false;
        }
        for (int k = 0; k < 3; ++k) out[k] = v[k];
        set(key);
        return true;
    }
    // An unsigned integer: a non-negative integer, or a whole real up to 2^53.
    bool unsigned_integer(const cv::FileNode &n, const std::string &key, uint64_t *out) {
        double d = 0.0;
        if (!n.isInt() && !n.isReal()) return fail(key, n, "is not an unsigned integer");
        d = static_cast<double>(n);
        if (!(d >= 0.0 && d <= 9007199254740992.0) || d != std::floor(d)) {
            return fail(key, n, "is not an unsigned integer (0..2^53)");
        }
        *out = static_cast<uint64_t>(d);
        set(key);
        return true;
    }
    // Refuses keys of `map` that are not in `known` (prefix: "filter." for the sub-maps).
    bool only_known(const cv::FileNode &map, const std::set<std::string> &known,
                    const std::string &prefix) {
        for (const std::string &key : map.keys()) {
            if (known.count(key) == 0) {
                *error_ = path_;
                const std::string q = quoted(key);  // one line, whatever the key holds
                const bool plain = q.size() == key.size() + 2 && q.compare(1, key.size(), key) == 0;
                error_->append(": unknown key ").append(prefix).append(plain ? key : q);
                return false;
            }
        }
        return true;
    }

  private:
    const std::string &path_;
    AppConfig *cfg_;
    std::string *error_;
};

}  // namespace

static bool read_config_impl(const std::string &path, AppConfig *cfg, std::string *error);

// One line: an exception's message may hold line breaks.
static std::string one_line(std::string m) {
    for (char &c : m) {
        if (c == '\n' || c == '\r') c = ' ';
    }
    while (!m.empty() && m.back() == ' ') m.pop_back();
    return m;
}

// cv::FileStorage throws more than cv::Exception on some malformed files (std::length_error,
// found by fuzz.config): any exception is a refused file, never a crash.
bool read_config(const std::string &path, AppConfig *cfg, std::string *error) {
    quiet_opencv();  // the reason goes into *error, once
    try {
        return read_config_impl(path, cfg, error);
    } catch (const cv::Exception &e) {
        *error = opencv_yaml_error(path, e);
    } catch (const std::exception &e) {
        *error = path + ": not valid YAML (" + one_line(e.what()) + ")";
    } catch (...) {
        *error = path + ": not valid YAML (unknown error)";
    }
    return false;
}

// The configuration is the small subset of YAML that apps/config/sfd.yaml uses. The first line
// is "%YAML:1.0" (without it cv::FileStorage refuses the file as "Input file is invalid", which
// names neither the line nor the cause). Every line is
// blank, a comment, the "%YAML:1.0" / "---" header, or "KEY:" / "KEY: VALUE" (KEY a name of
// letters, digits and '_', any indentation; lists are written [a, b, c]), in printable ASCII
// (tabs and, in comments, UTF-8 allowed). Anything else is refused here, before cv::FileStorage
// sees it: fuzz.config found small files on which cv::FileStorage::open never returns (a
// "--/-" line after a key; "-" list items below an indented key).
static bool config_lines_ok(const std::string &path, std::string *error) {
    std::ifstream in(path, std::ios::binary);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
        ++n;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const auto bad = [&](const char *why) {
            *error = path + ":" + std::to_string(n) + ": " + why;
            return false;
        };
        if (n == 1 && line != "%YAML:1.0" && line != "%YAML 1.0") {
            return bad(
                "the first line must be %YAML:1.0 (cv::FileStorage, which reads the "
                "configuration, takes no file without it)");
        }
        size_t i = line.find_first_not_of(" \t");
        if (i == std::string::npos) continue;  // blank
        const bool comment = line[i] == '#';
        for (size_t k = 0; k < line.size(); ++k) {
            const unsigned char c = static_cast<unsigned char>(line[k]);
            if (c == '\t' || (c >= 0x20 && c < 0x7f) || (comment && k > i && c >= 0x80)) continue;
            return bad("a control character or a non-ASCII byte outside a comment");
        }
        if (comment) continue;
        if (n <= 2 && (line == "%YAML:1.0" || line == "%YAML 1.0" || line == "---")) continue;
        size_t k = i;
        while (k < line.size() &&
               (std::isalnum(static_cast<unsigned char>(line[k])) || line[k] == '_')) {
            ++k;
        }
        if (k == i || std::isdigit(static_cast<unsigned char>(line[i])) || k >= line.size() ||
            line[k] != ':' || (k + 1 < line.size() && line[k + 1] != ' ' && line[k + 1] != '\t')) {
            return bad(
                "not a 'key: value' line (the configuration is the YAML subset of "
                "apps/config/sfd.yaml)");
        }
    }
    return true;
}

static bool read_config_impl(const std::string &path, AppConfig *cfg, std::string *error) {
    // Checked here first: cv::FileStorage would log its own line on stderr besides the reason.
    struct stat st;
    if (stat(path.c_str(), &st) != 0) {
        *error = path + ": cannot open (" + std::strerror(errno) + ")";
        return false;
    }
    if (!S_ISREG(st.st_mode)) {
        *error = path + ": not a regular file";
        return false;
    }
    if (!std::ifstream(path).is_open()) {
        *error = path + ": cannot open for reading";
        return false;
    }
    if (st.st_size == 0) {  // cv::FileStorage asserts on an empty buffer
        *error = path + ": empty file, not a YAML configuration";
        return false;
    }
    if (!config_lines_ok(path, error)) return false;
    cv::FileStorage fs;
    try {
        if (!fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML)) {
            *error = path + ": cannot open";
            return false;
        }
    } catch (const cv::Exception &e) {
        *error = opencv_yaml_error(path, e);
        return false;
    }
    const cv::FileNode root = fs.root();
    if (!root.isMap()) {
        *error = path + ": top level is not a map";
        return false;
    }
    Reader rd(path, cfg, error);
    static const std::set<std::string> known = {"method",
                                                "false_alarm_rate",
                                                "pixel_sigma_px",
                                                "window_frames",
                                                "group_size",
                                                "translation_known",
                                                "exact_depth_covariance",
                                                "parity_isolation",
                                                "pixel_noise_adapt",
                                                "evidence_frames",
                                                "both_parity_share",
                                                "alarm_hold_ratio",
                                                "alarm_hold_frames",
                                                "alarm_hold_max_statistic",
                                                "alarm_hold_min_statistic",
                                                "alarm_hold_alpha_scale",
                                                "alarm_hold_direction_alpha",
                                                "evidence_ramp_share",
                                                "default_depth_m",
                                                "default_depth_var_m2",
                                                "max_imu_gap_us",
                                                "time_horizon_us",
                                                "time_resync_messages",
                                                "gyro_bias_rad_s",
                                                "camera_id",
                                                "publish_timing",
                                                "lcm_url",
                                                "channels",
                                                "max_hypotheses",
                                                "ransac_confidence",
                                                "seed",
                                                "filter"};
    if (!rd.only_known(root, known, "")) return false;
    if (!check_integer_literals(path, error)) return false;
    sfd_params_t &p = cfg->node.params;
    if (!root["method"].empty()) {
        std::string s;
        if (!rd.string(root["method"], "method", &s)) return false;
        if (!set_method(s, cfg, error)) return rd.fail("method", root["method"], "is " + *error);
    }
    struct NumKey {
        const char *name;
        double *dst;
    } nums[] = {{"false_alarm_rate", &p.false_alarm_rate},
                {"pixel_sigma_px", &p.pixel_sigma_px},
                {"both_parity_share", &p.both_parity_share},
                {"alarm_hold_ratio", &p.alarm_hold_ratio},
                {"alarm_hold_max_statistic", &p.alarm_hold_max_statistic},
                {"alarm_hold_min_statistic", &p.alarm_hold_min_statistic},
                {"alarm_hold_alpha_scale", &p.alarm_hold_alpha_scale},
                {"alarm_hold_direction_alpha", &p.alarm_hold_direction_alpha},
                {"evidence_ramp_share", &p.evidence_ramp_share},
                {"default_depth_m", &p.default_depth_m},
                {"default_depth_var_m2", &p.default_depth_var_m2},
                {"ransac_confidence", &p.ransac_confidence}};
    for (const NumKey &k : nums) {
        if (!root[k.name].empty() && !rd.number(root[k.name], k.name, k.dst)) return false;
    }
    struct IntKey {
        const char *name;
        int *dst;
    } ints[] = {{"window_frames", &p.window_frames},
                {"group_size", &p.group_size},
                {"translation_known", &p.translation_known},
                {"exact_depth_covariance", &p.exact_depth_covariance},
                {"parity_isolation", &p.parity_isolation},
                {"pixel_noise_adapt", &p.pixel_noise_adapt},
                {"evidence_frames", &p.evidence_frames},
                {"alarm_hold_frames", &p.alarm_hold_frames},
                {"max_hypotheses", &p.max_hypotheses}};
    for (const IntKey &k : ints) {
        if (!root[k.name].empty() && !rd.integer(root[k.name], k.name, k.dst)) return false;
    }
    if (!root["publish_timing"].empty() &&
        !rd.integer(root["publish_timing"], "publish_timing", &cfg->node.publish_timing)) {
        return false;
    }
    if (!root["camera_id"].empty() &&
        !rd.integer(root["camera_id"], "camera_id", &cfg->node.camera_id)) {
        return false;
    }
    if (!root["max_imu_gap_us"].empty() &&
        !rd.micros(root["max_imu_gap_us"], "max_imu_gap_us", &p.max_imu_gap_us)) {
        return false;
    }
    if (!root["time_horizon_us"].empty() &&
        !rd.micros(root["time_horizon_us"], "time_horizon_us", &cfg->node.time.horizon_us)) {
        return false;
    }
    if (!root["time_resync_messages"].empty() &&
        !rd.integer(root["time_resync_messages"], "time_resync_messages",
                    &cfg->node.time.resync_messages)) {
        return false;
    }
    if (!root["gyro_bias_rad_s"].empty() &&
        !rd.vec3(root["gyro_bias_rad_s"], "gyro_bias_rad_s", p.gyro_bias_rad_s)) {
        return false;
    }
    if (!root["seed"].empty() && !rd.unsigned_integer(root["seed"], "seed", &p.seed)) {
        return false;
    }
    const cv::FileNode flt = root["filter"];
    if (!flt.empty()) {
        if (!flt.isMap()) return rd.fail("filter", flt, "is not a map");
        sfd_nav_config_t &nv = cfg->node.nav;
        struct FKey {
            const char *name;
            double *dst;
        } fnums[] = {{"gyro_noise_rad_s_rthz", &nv.noise.gyro_noise_rad_s_rthz},
                     {"accel_noise_m_s2_rthz", &nv.noise.accel_noise_m_s2_rthz},
                     {"gyro_bias_rw_rad_s2_rthz", &nv.noise.gyro_bias_rw_rad_s2_rthz},
                     {"accel_bias_rw_m_s3_rthz", &nv.noise.accel_bias_rw_m_s3_rthz},
                     {"gravity_m_s2", &nv.noise.gravity_m_s2},
                     {"init_rest_s", &nv.init_rest_s},
                     {"landmark_depth_var_m2", &nv.landmark_depth_var_m2},
                     {"landmark_max_age_s", &nv.landmark_max_age_s},
                     {"landmark_gate_alpha", &nv.landmark_gate_alpha},
                     {"min_parallax_px", &nv.min_parallax_px},
                     {"window_gate_alpha", &nv.window_gate_alpha},
                     {"keyframe_parallax_rad", &nv.keyframe_parallax_rad}};
        struct FInt {
            const char *name;
            int32_t *dst;
        } fints[] = {{"enabled", &nv.enabled},
                     {"gyro_bias_at_rest", &nv.gyro_bias_at_rest},
                     {"init_from_truth", &nv.init_from_truth},
                     {"consider_position", &nv.consider_position},
                     {"window_filter", &nv.window_filter},
                     {"window_size", &nv.window_size},
                     {"window_depth_priors", &nv.window_depth_priors},
                     {"window_flagged_earlier", &nv.window_flagged_earlier},
                     {"first_estimates", &nv.first_estimates},
                     {"observability_constrained", &nv.observability_constrained}};
        std::set<std::string> fknown = {"init_accel_bias_m_s2"};
        for (const FKey &k : fnums) fknown.insert(k.name);
        for (const FInt &k : fints) fknown.insert(k.name);
        if (!rd.only_known(flt, fknown, "filter.")) return false;
        for (const FKey &k : fnums) {
            if (!flt[k.name].empty() &&
                !rd.number(flt[k.name], std::string("filter.") + k.name, k.dst)) {
                return false;
            }
        }
        if (!flt["init_accel_bias_m_s2"].empty() &&
            !rd.vec3(flt["init_accel_bias_m_s2"], "filter.init_accel_bias_m_s2",
                     nv.init_accel_bias_m_s2)) {
            return false;
        }
        for (const FInt &k : fints) {
            if (!flt[k.name].empty() &&
                !rd.integer(flt[k.name], std::string("filter.") + k.name, k.dst)) {
                return false;
            }
        }
    }
    if (!root["lcm_url"].empty() && !rd.string(root["lcm_url"], "lcm_url", &cfg->lcm_url)) {
        return false;
    }
    const cv::FileNode ch = root["channels"];
    if (!ch.empty()) {
        if (!ch.isMap()) return rd.fail("channels", ch, "is not a map");
        std::string *dst[] = {&cfg->channels.imu,      &cfg->channels.camera_info,
                              &cfg->channels.features, &cfg->channels.verdict,
                              &cfg->channels.timing,   &cfg->channels.state,
                              &cfg->channels.truth};
        const char *names[] = {"imu",    "camera_info", "features", "verdict",
                               "timing", "state",       "truth"};
        if (!rd.only_known(ch, std::set<std::string>(std::begin(names), std::end(names)),
                           "channels.")) {
            return false;
        }
        for (int k = 0; k < 7; ++k) {
            if (!ch[names[k]].empty() &&
                !rd.string(ch[names[k]], std::string("channels.") + names[k], dst[k])) {
                return false;
            }
        }
    }
    return true;
}

// ---- validation -------------------------------------------------------------------------------

namespace {

std::string bound(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

// The checks of validate(): the first failure names the key's origin, the key and its value.
class Checker {
  public:
    Checker(const AppConfig &cfg, std::string *error) : cfg_(cfg), error_(error) {}
    bool failed() const { return failed_; }

    void fail(const std::string &key, const std::string &value, const std::string &why) {
        if (failed_) return;
        failed_ = true;
        *error_ = cfg_.origin_of(key) + ": " + key + ": " + value + " " + why;
    }
    void flag(const std::string &key, long long v) {
        if (v != 0 && v != 1) fail(key, std::to_string(v), "is not 0 or 1");
    }
    void integer(const std::string &key, long long v, long long lo, long long hi) {
        if (v < lo || v > hi) {
            fail(key, std::to_string(v),
                 "is not in " + std::to_string(lo) + ".." + std::to_string(hi));
        }
    }
    void finite(const std::string &key, double v) {
        if (!std::isfinite(v)) fail(key, format_double(v), "is not finite");
    }
    void positive(const std::string &key, double v) {
        finite(key, v);
        if (!(v > 0.0)) fail(key, format_double(v), "is not > 0");
    }
    void non_negative(const std::string &key, double v) {
        finite(key, v);
        if (!(v >= 0.0)) fail(key, format_double(v), "is not >= 0");
    }
    // lo <= v <= hi.
    void closed_interval(const std::string &key, double v, double lo, double hi) {
        finite(key, v);
        if (!(v >= lo && v <= hi)) {
            fail(key, format_double(v), "is not in [" + bound(lo) + ", " + bound(hi) + "]");
        }
    }
    // lo <= v < hi.
    void half_open_interval(const std::string &key, double v, double lo, double hi) {
        finite(key, v);
        if (!(v >= lo && v < hi)) {
            fail(key, format_double(v), "is not in [" + bound(lo) + ", " + bound(hi) + ")");
        }
    }
    // lo < v < hi, or lo < v <= hi with hi_closed.
    void open_interval(const std::string &key, double v, double lo, double hi, bool hi_closed) {
        finite(key, v);
        if (!(v > lo && (hi_closed ? v <= hi : v < hi))) {
            fail(key, format_double(v),
                 "is not in (" + bound(lo) + ", " + bound(hi) + (hi_closed ? "]" : ")"));
        }
    }
    void channel(const std::string &key, const std::string &name) {
        if (name.empty()) {
            fail(key, "\"\"", "is empty");
        } else if (name.size() > kLcmChannelMax) {
            fail(key, quoted(name),
                 "is longer than " + std::to_string(kLcmChannelMax) + " characters (LCM's limit)");
        } else {
            for (const char c : name) {
                if (std::string(".[]{}()*+?^$|\\").find(c) != std::string::npos ||
                    std::isgraph(static_cast<unsigned char>(c)) == 0) {
                    std::string q = quoted(std::string(1, c));  // escaped, one line
                    q.front() = '\'';
                    q.back() = '\'';
                    fail(key, quoted(name),
                         "contains " + q +
                             " (a channel name is matched exactly: no blanks, control or "
                             "regular-expression characters)");
                    return;
                }
            }
        }
    }

  private:
    static constexpr size_t kLcmChannelMax = 63;  // LCM_MAX_CHANNEL_NAME_LENGTH of <lcm/lcm.h>
    const AppConfig &cfg_;
    std::string *error_;
    bool failed_ = false;
};

}  // namespace

bool validate(const AppConfig &cfg, std::string *error) {
    Checker c(cfg, error);
    const sfd_params_t &p = cfg.node.params;
    const sfd_nav_config_t &nv = cfg.node.nav;
    const sfd_ekf_noise_t &nz = nv.noise;
    // The detector (sfd_params_validate), in the order of apps/config/sfd.yaml.
    if (!(p.method >= 0 && p.method < kNumMethods && cfg.method == kMethods[p.method])) {
        c.fail("method", quoted(cfg.method), std::string("is not one of ") + kMethodList);
    }
    c.open_interval("false_alarm_rate", p.false_alarm_rate, 0.0, 0.5, true);
    c.positive("pixel_sigma_px", p.pixel_sigma_px);
    c.integer("window_frames", p.window_frames, 2, SFD_MAX_WINDOW);
    c.integer("group_size", p.group_size, 1, SFD_MAX_GROUP);
    c.flag("translation_known", p.translation_known);
    c.flag("exact_depth_covariance", p.exact_depth_covariance);
    c.flag("parity_isolation", p.parity_isolation);
    c.flag("pixel_noise_adapt", p.pixel_noise_adapt);
    c.integer("evidence_frames", p.evidence_frames, 0, SFD_MAX_WINDOW);
    c.open_interval("both_parity_share", p.both_parity_share, 0.0, 1.0, false);
    c.open_interval("alarm_hold_ratio", p.alarm_hold_ratio, 0.0, 1.0, true);
    c.integer("alarm_hold_frames", p.alarm_hold_frames, 1, SFD_ALARM_HOLD_MAX_FRAMES);
    c.closed_interval("alarm_hold_max_statistic", p.alarm_hold_max_statistic, 1.0, 1e6);
    c.closed_interval("alarm_hold_min_statistic", p.alarm_hold_min_statistic, 0.0, 1.0);
    c.open_interval("alarm_hold_alpha_scale", p.alarm_hold_alpha_scale, 0.0, 1.0, true);
    c.half_open_interval("alarm_hold_direction_alpha", p.alarm_hold_direction_alpha, 0.0, 0.5);
    c.closed_interval("evidence_ramp_share", p.evidence_ramp_share, 0.0, 1.0);
    // stored as float by the parity detector (sfd_parity_obs_t)
    c.closed_interval("default_depth_m", p.default_depth_m, FLT_MIN, FLT_MAX);
    c.closed_interval("default_depth_var_m2", p.default_depth_var_m2, 0.0, FLT_MAX);
    if (p.max_imu_gap_us <= 0) {
        c.fail("max_imu_gap_us", std::to_string(p.max_imu_gap_us), "is not > 0");
    }
    // The time-glitch policy (sfd_time_guard_params_validate).
    if (cfg.node.time.horizon_us <= 0) {
        c.fail("time_horizon_us", std::to_string(cfg.node.time.horizon_us), "is not > 0");
    }
    c.integer("time_resync_messages", cfg.node.time.resync_messages, 2, 1000);
    for (int k = 0; k < 3; ++k) {
        c.finite("gyro_bias_rad_s[" + std::to_string(k) + "]", p.gyro_bias_rad_s[k]);
    }
    c.integer("max_hypotheses", p.max_hypotheses, 1, SFD_MAX_HYPOTHESES);
    c.open_interval("ransac_confidence", p.ransac_confidence, 0.0, 1.0, false);
    // The filter (sfd_nav_init, sfd_window_init, sfd_rest_init, sfd_ekf_init, sfd_assoc_init).
    c.flag("filter.enabled", nv.enabled);
    c.non_negative("filter.gyro_noise_rad_s_rthz", nz.gyro_noise_rad_s_rthz);
    c.non_negative("filter.accel_noise_m_s2_rthz", nz.accel_noise_m_s2_rthz);
    c.non_negative("filter.gyro_bias_rw_rad_s2_rthz", nz.gyro_bias_rw_rad_s2_rthz);
    c.non_negative("filter.accel_bias_rw_m_s3_rthz", nz.accel_bias_rw_m_s3_rthz);
    c.positive("filter.gravity_m_s2", nz.gravity_m_s2);
    c.flag("filter.window_filter", nv.window_filter);
    c.integer("filter.window_size", nv.window_size, 2, SFD_MAX_WINDOW);
    c.integer("filter.window_depth_priors", nv.window_depth_priors, 0, 2);
    c.flag("filter.window_flagged_earlier", nv.window_flagged_earlier);
    c.open_interval("filter.window_gate_alpha", nv.window_gate_alpha, 0.0, 0.5, true);
    c.flag("filter.first_estimates", nv.first_estimates);
    c.flag("filter.observability_constrained", nv.observability_constrained);
    c.non_negative("filter.keyframe_parallax_rad", nv.keyframe_parallax_rad);
    // Keyframes keep the parity window's older window_frames - 1 frames as the newest clones and
    // need at least one older clone besides (sfd_window_params_t.keyframe_recent).
    if (nv.keyframe_parallax_rad > 0.0 && nv.window_filter == 1 &&
        nv.window_size < p.window_frames + 1) {
        c.fail("filter.keyframe_parallax_rad", format_double(nv.keyframe_parallax_rad),
               "needs filter.window_size >= window_frames + 1 (" +
                   std::to_string(p.window_frames + 1) + ")");
    }
    c.open_interval("filter.init_rest_s", nv.init_rest_s, 0.0, 60.0, false);
    c.flag("filter.init_from_truth", nv.init_from_truth);
    for (int k = 0; k < 3; ++k) {
        c.finite("filter.init_accel_bias_m_s2[" + std::to_string(k) + "]",
                 nv.init_accel_bias_m_s2[k]);
    }
    c.flag("filter.consider_position", nv.consider_position);
    c.flag("filter.gyro_bias_at_rest", nv.gyro_bias_at_rest);
    c.non_negative("filter.landmark_depth_var_m2", nv.landmark_depth_var_m2);
    // > 0 (sfd_nav_init); at most 9e9 s, so that the age in microseconds fits in an int64.
    c.open_interval("filter.landmark_max_age_s", nv.landmark_max_age_s, 0.0, kMaxMicros * 1e-6,
                    true);
    c.open_interval("filter.landmark_gate_alpha", nv.landmark_gate_alpha, 0.0, 1.0, false);
    c.non_negative("filter.min_parallax_px", nv.min_parallax_px);
    // Not keys of the file (programs that fill the struct): the core's ranges all the same.
    c.positive("filter.max_dt_s", nz.max_dt_s);
    for (int k = 0; k < SFD_EKF_DIM; ++k) {
        c.non_negative("filter.p0_diag[" + std::to_string(k) + "]", nv.p0_diag[k]);
    }
    // The node.
    if (cfg.node.camera_id < -1) {
        c.fail("camera_id", std::to_string(cfg.node.camera_id),
               "is not -1 or in 0.." + std::to_string(std::numeric_limits<int32_t>::max()));
    }
    c.flag("publish_timing", cfg.node.publish_timing);
    if (cfg.lcm_url.empty()) c.fail("lcm_url", "\"\"", "is empty");
    const std::string *names[] = {&cfg.channels.imu,      &cfg.channels.camera_info,
                                  &cfg.channels.features, &cfg.channels.verdict,
                                  &cfg.channels.timing,   &cfg.channels.state,
                                  &cfg.channels.truth};
    const char *keys[] = {"channels.imu",     "channels.camera_info", "channels.features",
                          "channels.verdict", "channels.timing",      "channels.state",
                          "channels.truth"};
    constexpr int kChannels = static_cast<int>(sizeof keys / sizeof keys[0]);
    for (int k = 0; k < kChannels; ++k) c.channel(keys[k], *names[k]);
    for (int k = 1; k < kChannels; ++k) {
        for (int j = 0; j < k; ++j) {
            if (*names[k] == *names[j]) {  // named: the one that was set (a default is not)
                const bool first =
                    cfg.origin_of(keys[k]) == "default" && cfg.origin_of(keys[j]) != "default";
                c.fail(first ? keys[j] : keys[k], quoted(*names[k]),
                       std::string("is the same as ") + (first ? keys[k] : keys[j]));
            }
        }
    }
    // Across keys (sfd_pipeline_init): the association methods run on the filter.
    const int m = p.method;
    if ((m == SFD_METHOD_OPRF || m == SFD_METHOD_RANSAC1 || m == SFD_METHOD_RANSACF ||
         m == SFD_METHOD_BOTH) &&
        nv.enabled == 0) {
        c.fail("method", quoted(cfg.method),
               "needs filter.enabled: 1 (it is 0, from " + cfg.origin_of("filter.enabled") + ")");
    }
    if (c.failed()) return false;
    // The core's own validators: a range above that differs from theirs is a bug of this file.
    sfd_status_t st = sfd_params_validate(&p);
    if (st == SFD_OK) st = sfd_time_guard_params_validate(&cfg.node.time);
    if (st != SFD_OK) {
        *error = std::string("internal: the core refuses a configuration validate() accepts (") +
                 sfd_status_str(st) + ")";
        return false;
    }
    return true;
}

bool load_config(const std::string &path, AppConfig *cfg, std::string *error) {
    return read_config(path, cfg, error) && validate(*cfg, error);
}

bool parse_long(const char *s, long lo, long hi, long *out) {
    char *end = nullptr;
    errno = 0;
    const long v = std::strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno != 0 || v < lo || v > hi) return false;
    *out = v;
    return true;
}

}  // namespace sfdapp
