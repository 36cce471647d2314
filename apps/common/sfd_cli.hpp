// SPDX-License-Identifier: MIT
// The one command-line convention of every sfd executable (docs/deploy.md, "Command line"):
// GNU long options parsed by glibc's getopt_long, as `--opt value` or `--opt=value`; `--help`
// and `--version` on every tool and subcommand; a value that does not parse is exit 2 with the
// one line "PROG: --opt: VALUE is not ..."; an unknown option (an abbreviation included: names
// are matched whole, so that adding an option never changes what an old command line means) is
// exit 2 too. Progress lines on a terminal (Progress) live here as well.
#ifndef SFD_CLI_HPP
#define SFD_CLI_HPP

#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace sfdcli {

/// Exit code of bad usage and bad input files (SPEC "Commands").
constexpr int kExitUsage = 2;

/// Sets what an option means. `value` is the option's value ("" for a switch). On a bad value
/// returns false with `why` completing "VALUE ..." ("is not an integer").
using Setter = std::function<bool(const std::string &value, std::string *why)>;

struct Option {
    std::string name;      ///< the long name without "--" ("window-frames")
    char short_name = 0;   ///< a one-letter form ('o' for -o), or 0
    std::string metavar;   ///< the value's placeholder ("N"); empty: a switch (no value)
    std::string help;      ///< what it does; '\n' starts another line
    Setter set;            ///< called once per occurrence, in command-line order
    bool hidden = false;   ///< accepted, not listed in the help (an option of other subcommands)
    std::string alias_of;  ///< non-empty: a deprecated spelling of --alias_of (hidden from the
                           ///< help; using it prints one notice on stderr)
};

class Parser {
  public:
    /// `prog`: the executable's name, which starts every message ("sfd-sim"); `command`: what
    /// the help's usage line calls it ("sfd-sim paper-uav"); `usage`: the rest of that line.
    Parser(std::string prog, std::string command, std::string usage, std::string description);

    /// A heading in the help above the options added after it.
    void section(const std::string &title);
    void add(Option option);
    /// A switch (no value).
    void flag(const std::string &name, const std::string &help, const std::function<void()> &on);
    /// An option with a value.
    void value(const std::string &name, const std::string &metavar, const std::string &help,
               Setter set);
    /// A deprecated spelling `old_name` of the option `new_name` (added before).
    void alias(const std::string &old_name, const std::string &new_name);
    /// Text after the options in the help (exit codes, notes).
    void epilog(const std::string &text);
    /// More help, printed after the description by `print` (a subcommand's notes).
    void extra_help(std::function<void(std::FILE *)> print);

    /// Parses argv[1..argc-1]; the words that are not options (and every word after "--") go to
    /// *positional, in order. Returns -1 when the program should go on, 0 after --help or
    /// --version (printed on stdout), kExitUsage after a usage error (one line on stderr).
    int parse(int argc, char **argv, std::vector<std::string> *positional);

    void print_help(std::FILE *f) const;
    /// Prints "PROG: MESSAGE" on stderr and returns kExitUsage.
    int fail(const std::string &message) const;
    const std::string &prog() const { return prog_; }

  private:
    struct Entry {
        Option option;
        std::string section;
    };
    std::string prog_, command_, usage_, description_, epilog_, section_;
    std::vector<Entry> entries_;
    std::function<void(std::FILE *)> extra_help_;
};

/// "MAJOR.MINOR.PATCH" of sfd_version.h (SFD_VERSION_*), as the tools built with it print it.
std::string version_string();

/// Values as the options take them: the whole text, else false with `why`.
bool parse_int(const std::string &text, long long lo, long long hi, long long *out,
               std::string *why);
bool parse_real(const std::string &text, double lo, double hi, double *out, std::string *why);

/// A Setter that parses an integer in [lo, hi] (parse_int) into *dst, of any integer type.
template <typename Int>
Setter int_setter(Int *dst, long long lo, long long hi) {
    return [dst, lo, hi](const std::string &v, std::string *why) {
        long long x = 0;
        if (!parse_int(v, lo, hi, &x, why)) return false;
        *dst = static_cast<Int>(x);
        return true;
    };
}

/// A Setter that parses a finite real in [lo, hi] (parse_real) into *dst.
inline Setter real_setter(double *dst, double lo, double hi) {
    return [dst, lo, hi](const std::string &v, std::string *why) {
        return parse_real(v, lo, hi, dst, why);
    };
}
/// "X,Y,Z": three finite numbers.
bool parse_vec3(const std::string &text, double out[3], std::string *why);

/// True when progress lines are wanted: stderr is a terminal and the environment variable CI is
/// unset or empty (outputs never depend on it).
bool progress_wanted();

/// A progress line on stderr ("PROG: 1200 frames, 830 frames/s, 40%, 3 s left"), rewritten in
/// place at most twice a second, only when progress_wanted(); silent otherwise.
class Progress {
  public:
    Progress(std::string prog, std::string unit);
    /// `done` items so far; `fraction` of the whole work done, in [0, 1] (< 0: unknown, no
    /// percentage or time left).
    void update(long long done, double fraction);
    /// The last line (totals and time taken), ended with a newline; on a terminal only.
    void finish(long long done);
    /// Clears the progress line (if one is shown), so that text printed on stdout starts on a
    /// clean line; the next update() draws it again.
    void clear();
    bool enabled() const { return enabled_; }

  private:
    void print(long long done, double fraction, bool last);
    std::string prog_, unit_;
    bool enabled_;
    bool printed_ = false;
    std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace sfdcli

#endif
