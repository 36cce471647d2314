// SPDX-License-Identifier: MIT
#include "sfd_cli.hpp"

#include <getopt.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <utility>

#include "sfd/sfd_version.h"

namespace sfdcli {

namespace {

// getopt_long's `val` of the option at index k (above every character).
constexpr int kLongBase = 1000;

}  // namespace

Parser::Parser(std::string prog, std::string command, std::string usage, std::string description)
    : prog_(std::move(prog)),
      command_(std::move(command)),
      usage_(std::move(usage)),
      description_(std::move(description)) {}

void Parser::section(const std::string &title) {
    section_ = title;
}

void Parser::add(Option option) {
    entries_.push_back(Entry{std::move(option), section_});
}

void Parser::flag(const std::string &name, const std::string &help,
                  const std::function<void()> &on) {
    Option o;
    o.name = name;
    o.help = help;
    o.set = [on](const std::string &, std::string *) {
        on();
        return true;
    };
    add(std::move(o));
}

void Parser::value(const std::string &name, const std::string &metavar, const std::string &help,
                   Setter set) {
    Option o;
    o.name = name;
    o.metavar = metavar;
    o.help = help;
    o.set = std::move(set);
    add(std::move(o));
}

void Parser::alias(const std::string &old_name, const std::string &new_name) {
    for (const Entry &e : entries_) {
        if (e.option.name == new_name) {
            Option o = e.option;
            o.name = old_name;
            o.short_name = 0;
            o.alias_of = new_name;
            entries_.push_back(Entry{std::move(o), e.section});
            return;
        }
    }
}

void Parser::epilog(const std::string &text) {
    epilog_ = text;
}

void Parser::extra_help(std::function<void(std::FILE *)> print) {
    extra_help_ = std::move(print);
}

int Parser::fail(const std::string &message) const {
    std::fprintf(stderr, "%s: %s\n", prog_.c_str(), message.c_str());
    return kExitUsage;
}

void Parser::print_help(std::FILE *f) const {
    std::fprintf(f, "usage: %s %s\n", command_.c_str(), usage_.c_str());
    if (!description_.empty()) std::fprintf(f, "%s\n", description_.c_str());
    if (extra_help_) extra_help_(f);
    std::string section = "\x01";  // none printed yet
    constexpr size_t kColumn = 28;
    for (const Entry &e : entries_) {
        const Option &o = e.option;
        if (!o.alias_of.empty() || o.hidden) continue;
        if (e.section != section) {
            section = e.section;
            std::fprintf(f, "%s:\n", section.empty() ? "Options" : section.c_str());
        }
        std::string left = "  ";
        if (o.short_name != 0) left.append("-").append(1, o.short_name).append(", ");
        left += "--" + o.name;
        if (!o.metavar.empty()) left += " " + o.metavar;
        size_t start = 0;
        bool first = true;
        do {
            const size_t nl = o.help.find('\n', start);
            const std::string line =
                o.help.substr(start, nl == std::string::npos ? nl : nl - start);
            if (first && left.size() + 1 < kColumn) {
                std::fprintf(f, "%-*s%s\n", static_cast<int>(kColumn), left.c_str(), line.c_str());
            } else {
                if (first) std::fprintf(f, "%s\n", left.c_str());
                std::fprintf(f, "%*s%s\n", static_cast<int>(kColumn), "", line.c_str());
            }
            first = false;
            start = nl == std::string::npos ? nl : nl + 1;
        } while (start != std::string::npos);
    }
    std::fprintf(f, "General:\n");
    std::fprintf(f, "%-*s%s\n", static_cast<int>(kColumn), "  -h, --help",
                 "this help, then exit 0");
    std::fprintf(f, "%-*s%s\n", static_cast<int>(kColumn), "  --version",
                 ("print \"" + prog_ + " " + version_string() + "\", then exit 0").c_str());
    std::fprintf(f,
                 "Options take their value as --opt VALUE or --opt=VALUE; names are matched whole "
                 "(no\nabbreviations); \"--\" ends the options.\n");
    if (!epilog_.empty()) std::fprintf(f, "%s\n", epilog_.c_str());
}

int Parser::parse(int argc, char **argv, std::vector<std::string> *positional) {
    std::vector<option> longopts;
    longopts.reserve(entries_.size() + 3);
    std::string shortopts = "+:h";  // '+': stop at the first non-option (handled below)
    for (size_t k = 0; k < entries_.size(); ++k) {
        const Option &o = entries_[k].option;
        longopts.push_back(option{o.name.c_str(),
                                  o.metavar.empty() ? no_argument : required_argument, nullptr,
                                  kLongBase + static_cast<int>(k)});
        if (o.short_name != 0) {
            shortopts += o.short_name;
            if (!o.metavar.empty()) shortopts += ':';
        }
    }
    const int kHelp = kLongBase - 1, kVersion = kLongBase - 2;
    longopts.push_back(option{"help", no_argument, nullptr, kHelp});
    longopts.push_back(option{"version", no_argument, nullptr, kVersion});
    longopts.push_back(option{nullptr, 0, nullptr, 0});
    const std::string hint = " (" + command_ + " --help lists the options)";
    opterr = 0;
    optind = 0;  // glibc: start afresh (a parser may run after another)
    bool first_call = true;
    while (first_call || optind < argc) {
        // The word getopt_long reads next: with '+', no permutation, so argv[before] is it.
        const int before = first_call ? 1 : optind;
        first_call = false;
        int index = -1;
        const int c = getopt_long(argc, argv, shortopts.c_str(), longopts.data(), &index);
        if (c == -1) {
            if (optind >= argc) break;
            if (optind > before && std::strcmp(argv[optind - 1], "--") == 0) {
                for (int k = optind; k < argc; ++k) positional->emplace_back(argv[k]);
                break;
            }
            positional->emplace_back(argv[optind]);
            ++optind;
            continue;
        }
        const std::string word = before < argc ? argv[before] : "";
        const std::string name = word.rfind("--", 0) == 0 ? word.substr(2, word.find('=') - 2) : "";
        if (c == '?') {
            if (optopt != 0 && word.rfind("--", 0) != 0) {
                return fail(std::string("unknown option -") + static_cast<char>(optopt) + hint);
            }
            if (optopt >= kLongBase || optopt == kHelp || optopt == kVersion) {
                return fail("--" + name + " takes no value");  // "--switch=value"
            }
            return fail("unknown option " + word.substr(0, word.find('=')) + hint);
        }
        if (c == ':') return fail((name.empty() ? word : "--" + name) + " needs a value");
        if (!name.empty() && index >= 0 && name != longopts[static_cast<size_t>(index)].name) {
            return fail(std::string("unknown option --").append(name).append(hint));  // abbreviated
        }
        if (c == 'h' || c == kHelp) {
            print_help(stdout);
            return 0;
        }
        if (c == kVersion) {
            std::printf("%s %s\n", prog_.c_str(), version_string().c_str());
            return 0;
        }
        size_t k = entries_.size();
        if (c >= kLongBase) {
            k = static_cast<size_t>(c - kLongBase);
        } else {
            for (size_t j = 0; j < entries_.size(); ++j) {
                if (entries_[j].option.short_name == c) k = j;
            }
        }
        if (k >= entries_.size())
            return fail(std::string("unknown option ").append(word).append(hint));
        const Option &o = entries_[k].option;
        const std::string shown =
            o.short_name == c ? std::string("-") + o.short_name : "--" + o.name;
        if (!o.alias_of.empty()) {
            std::fprintf(stderr, "%s: %s is deprecated: use --%s\n", prog_.c_str(), shown.c_str(),
                         o.alias_of.c_str());
        }
        const std::string value = o.metavar.empty() || optarg == nullptr ? "" : optarg;
        std::string why;
        if (!o.set(value, &why)) {
            std::string message = shown + ": ";
            if (!o.metavar.empty()) message.append(value.empty() ? "\"\"" : value).append(" ");
            return fail(message.append(why));
        }
    }
    return -1;
}

std::string version_string() {
#ifdef SFD_VERSION_PATCH
    const int patch = SFD_VERSION_PATCH;
#else
    const int patch = 0;  // sfd_version.h without a patch level: the release is MAJOR.MINOR.0
#endif
    return std::to_string(SFD_VERSION_MAJOR) + "." + std::to_string(SFD_VERSION_MINOR) + "." +
           std::to_string(patch);
}

bool parse_int(const std::string &text, long long lo, long long hi, long long *out,
               std::string *why) {
    const char *s = text.c_str();
    char *end = nullptr;
    errno = 0;
    const long long v = std::strtoll(s, &end, 10);
    if (text.empty() || end == s || *end != '\0') {
        *why = "is not an integer";
        return false;
    }
    if (errno == ERANGE || v < lo || v > hi) {
        *why = "is not in " + std::to_string(lo) + ".." + std::to_string(hi);
        return false;
    }
    *out = v;
    return true;
}

bool parse_real(const std::string &text, double lo, double hi, double *out, std::string *why) {
    const char *s = text.c_str();
    char *end = nullptr;
    const double v = std::strtod(s, &end);
    if (text.empty() || end == s || *end != '\0') {
        *why = "is not a number";
        return false;
    }
    if (!(v >= lo && v <= hi)) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "is not in %g..%g", lo, hi);
        *why = buf;
        return false;
    }
    *out = v;
    return true;
}

bool parse_vec3(const std::string &text, double out[3], std::string *why) {
    double v[3];
    const char *p = text.c_str();
    for (int k = 0; k < 3; ++k) {
        char *end = nullptr;
        v[k] = std::strtod(p, &end);
        if (end == p || !std::isfinite(v[k]) || *end != (k < 2 ? ',' : '\0')) {
            *why = "is not three finite numbers X,Y,Z";
            return false;
        }
        p = end + 1;
    }
    for (int k = 0; k < 3; ++k) out[k] = v[k];
    return true;
}

bool progress_wanted() {
    const char *ci = std::getenv("CI");
    return isatty(STDERR_FILENO) != 0 && (ci == nullptr || *ci == '\0');
}

Progress::Progress(std::string prog, std::string unit)
    : prog_(std::move(prog)),
      unit_(std::move(unit)),
      enabled_(progress_wanted()),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

void Progress::update(long long done, double fraction) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(500)) return;  // at most twice a second
    last_ = now;
    print(done, fraction, false);
}

void Progress::finish(long long done) {
    if (enabled_) print(done, 1.0, true);  // the totals, once, on a terminal
}

void Progress::clear() {
    if (!enabled_ || !printed_) return;
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
    printed_ = false;
}

void Progress::print(long long done, double fraction, bool last) {
    const double elapsed_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    char line[200];
    int n =
        std::snprintf(line, sizeof line, "%s: %lld %s, %.0f %s/s", prog_.c_str(), done,
                      unit_.c_str(), elapsed_s > 0 ? double(done) / elapsed_s : 0.0, unit_.c_str());
    if (last) {
        std::snprintf(line + n, sizeof line - size_t(n), ", done in %.1f s", elapsed_s);
    } else if (fraction > 0.0 && fraction <= 1.0) {
        const double left_s = elapsed_s * (1.0 - fraction) / fraction;
        std::snprintf(line + n, sizeof line - size_t(n), ", %.0f%%, %.0f s left", 100.0 * fraction,
                      left_s);
    }
    // "\r" rewrites the line; "\033[K" clears what a longer line left behind.
    std::fprintf(stderr, "\r%s\033[K%s", line, last ? "\n" : "");
    std::fflush(stderr);
    printed_ = true;
}

}  // namespace sfdcli
