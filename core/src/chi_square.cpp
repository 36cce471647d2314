// SPDX-License-Identifier: MIT
// Chi-square distribution (sfd_chi2.h): regularized incomplete gamma functions, quantile,
// non-central CDF and the threshold table. Design note: core/docs/chi_square.md.
//
// Everything here works on the chi-square shape parameter a = k/2 held as the integer k
// ("twice a"), so that log Gamma is only ever needed at integer and half-integer arguments.
//
// Sources:
//  [NR]   Press et al., Numerical Recipes in C, 2nd ed., sec. 6.2: series (6.2.5) for P(a,x)
//         and the continued fraction (6.2.7) for Q(a,x), evaluated by the modified Lentz method
//         (sec. 5.2).
//  [AS]   Abramowitz & Stegun, Handbook of Mathematical Functions: 6.1.6 / 6.1.12 (Gamma at
//         integers and half-integers), 6.1.41 (Stirling series of log Gamma), 6.5.1-6.5.3
//         (P, Q), 6.5.29 / 6.5.31 (series / continued fraction), 26.2.23 (normal quantile
//         approximation), 26.4.17 (Wilson-Hilferty), 26.4.25 (non-central chi-square as a
//         Poisson mixture).
//  [L]    C. Loader, "Fast and accurate computation of binomial probabilities", 2000: the
//         saddle-point form of x^a e^-x / Gamma(a+1) through stirlerr() and bd0(), which avoids
//         the cancellation of a*log(x) - x - lgamma(a+1) for large a.
//  [BK]   Benton & Krishnamoorthy, Comput. Stat. Data Anal. 43 (2003) 249-267: summing the
//         Poisson mixture outward from the Poisson mode, with geometric tail bounds.
//
// Rules (core discipline): no heap, no exceptions, no recursion, no mutable global state, every
// loop bounded by a compile-time constant, only + - * / sqrt exp log from libm.
#include "core_private.hpp"

#include "sfd/sfd_chi2.h"

namespace {

// ---- Constants ----------------------------------------------------------------------------

constexpr double kLnSqrt2Pi = 0.91893853320467274178;  // log(sqrt(2 pi))
constexpr double kEps = 1.1102230246251565e-16;        // 2^-53, unit roundoff
constexpr double kTiny = 1.0e-300;                     // Lentz's "FPMIN" [NR 5.2]

// Domain limits of the public functions.
constexpr double kAlphaMin = 1.0e-300;
constexpr double kLambdaMax = 1000.0;

// Largest shape*2 the internal incomplete gamma accepts: the central range plus every term
// the non-central mixture may reach (dof + 2j, j < mode + kNcMaxTerms, mode <= lambda/2).
constexpr int kNcMaxTerms = 2048;
constexpr int kMaxTwiceA =
    SFD_CHI2_MAX_DOF + 2 * (static_cast<int>(kLambdaMax / 2.0) + kNcMaxTerms);

// Above this shape stirlerr() uses the Stirling series directly (truncation error < 2e-16);
// below, it shifts the argument up by at most kStirlingShiftMax unit steps first.
constexpr int kStirlingTwiceA = 30;  // a <= 15
constexpr int kStirlingShiftMax = kStirlingTwiceA / 2 + 1;
constexpr int kAtanhMaxTerms = 40;  // t^2 <= 1/4: 4^-30 < 1e-18

// Iteration bounds. The series needs about sqrt(78 a) terms at x ~ a (product of x/(a+n)
// falling below 1e-17), the continued fraction fewer; both are far below the bound for
// a <= kMaxTwiceA / 2 (measured maxima in core/docs/chi_square.md).
constexpr int kGammaMaxIter = 4096;
constexpr int kBd0MaxTerms = 64;       // |v| < 0.1: each term gains a factor 100
constexpr int kQuantileMaxIter = 100;  // Newton/bisection steps (typically 3-8)

// Quantile solver: stop when the Newton step in log(x) is below this (relative step in x).
constexpr double kQuantileTolLogX = 1.0e-13;
constexpr double kQuantileMaxStep = 2.0;  // largest Newton step in log(x) (factor e^2)

// Mixture truncation: stop when the bound on the remaining mass is below this fraction of
// the sum (relative) — [BK] geometric tail bounds.
constexpr double kNcRelTol = 1.0e-17;

// ---- log Gamma at half-integers, Stirling error, deviance -----------------------------------

// Stirling error [L]: stirlerr(a) = log Gamma(a+1) - (a + 1/2) log(a) + a - log(sqrt(2 pi)),
// for a = twice_a/2 > 0. This replaces lgamma: log Gamma(a+1) at any integer or half-integer
// a follows from it exactly by that definition.
//  - a > 15: the Stirling series [AS 6.1.41]
//      1/(12a) - 1/(360a^3) + 1/(1260a^5) - 1/(1680a^7) + 1/(1188a^9)   (next term < 2e-16);
//  - a <= 15: shifted up by whole steps and brought back down with the recurrence that
//    log Gamma(a+2) = log Gamma(a+1) + log(a+1) implies,
//      stirlerr(a) = stirlerr(a+1) + (a + 1/2) log(1 + 1/a) - 1
//                  = stirlerr(a+1) + sum_{i>=1} t^(2i) / (2i+1),   t = 1/(2a+1) <= 1/2,
//    using log(1 + 1/a) = log((1+t)/(1-t)) = 2 atanh(t) [AS 4.6.22]: every term is positive,
//    so unlike lgamma(a+1) - (a+1/2) log(a) + ... nothing cancels (error ~1e-17 absolute).
// The exact alternative, log((n-1)!) or log(sqrt(pi) prod (i - 1/2)) [AS 6.1.6, 6.1.12], loses
// ~1e-14 to that cancellation at a ~ 12.
double stirlerr(int twice_a) {
    int ta = twice_a;
    for (int i = 0; i < kStirlingShiftMax; ++i) {  // shift a up past 15
        if (ta > kStirlingTwiceA) break;
        ta += 2;
    }
    const double big = 0.5 * static_cast<double>(ta);
    const double bb = big * big;
    constexpr double s0 = 1.0 / 12.0;
    constexpr double s1 = 1.0 / 360.0;
    constexpr double s2 = 1.0 / 1260.0;
    constexpr double s3 = 1.0 / 1680.0;
    constexpr double s4 = 1.0 / 1188.0;
    double se = (s0 - (s1 - (s2 - (s3 - s4 / bb) / bb) / bb) / bb) / big;
    for (int i = 0; i < kStirlingShiftMax; ++i) {  // and back down, one unit at a time
        if (ta <= twice_a) break;
        ta -= 2;
        const double t = 1.0 / static_cast<double>(ta + 1);  // 1 / (2a + 1)
        const double t2 = t * t;
        double pw = 1.0;
        double sum = 0.0;
        for (int j = 1; j <= kAtanhMaxTerms; ++j) {
            pw *= t2;
            const double term = pw / static_cast<double>(2 * j + 1);
            sum += term;
            if (term <= sum * (0.125 * kEps)) break;
        }
        se += sum;
    }
    return se;
}

// log Gamma(a + 1) at a = twice_a/2, from stirlerr (only used for a starting point).
double log_gamma_plus_one(int twice_a) {
    const double a = 0.5 * static_cast<double>(twice_a);
    return stirlerr(twice_a) + (a + 0.5) * std::log(a) - a + kLnSqrt2Pi;
}

// Deviance term [L]: bd0(a, m) = a log(a/m) + m - a >= 0, for a > 0, m > 0. Near a = m the
// direct form cancels; there it is summed as
//   (a-m) v + 2a sum_{j>=1} v^(2j+1)/(2j+1),  v = (a-m)/(a+m),  |v| < 0.1.
double bd0(double a, double m) {
    const double diff = a - m;
    if (std::fabs(diff) < 0.1 * (a + m)) {
        const double v = diff / (a + m);
        const double v2 = v * v;
        double s = diff * v;
        double ej = 2.0 * a * v;
        for (int j = 1; j <= kBd0MaxTerms; ++j) {
            ej *= v2;
            const double term = ej / static_cast<double>(2 * j + 1);
            s += term;
            if (std::fabs(term) <= kEps * 0.125 * std::fabs(s)) break;
        }
        return s;
    }
    return a * std::log(a / m) + m - a;
}

// log( m^a e^-m / Gamma(a+1) ), a = twice_a/2 > 0, m > 0: the log of the "Poisson probability"
// at a (non-integer allowed) with mean m, in Loader's saddle-point form [L]:
//   -stirlerr(a) - bd0(a, m) - log(sqrt(2 pi a)).
double log_poisson_term(int twice_a, double m) {
    const double a = 0.5 * static_cast<double>(twice_a);
    return -stirlerr(twice_a) - bd0(a, m) - kLnSqrt2Pi - 0.5 * std::log(a);
}

// ---- Regularized incomplete gamma functions ------------------------------------------------

struct GammaTails {
    double p;       // P(a, y)
    double q;       // Q(a, y) = 1 - P(a, y)
    double log_p;   // log P (finite even where P underflows)
    double log_q;   // log Q (finite even where Q underflows)
    double log_yg;  // log( y * g(y) ), g the Gamma(a,1) density: y^a e^-y / Gamma(a)
};

// P(a, y) and Q(a, y) for a = twice_a/2, 1 <= twice_a <= kMaxTwiceA, y > 0 finite [AS 6.5.1-2].
// The tail that is small in the region is computed directly and the other as its complement,
// which loses nothing: Q >= Q(1/2, 3/2) = 0.083 in the series region (y < a+1) and
// P >= 1/2 in the continued-fraction region (y >= a+1), so 1 - (small tail) is well
// conditioned. Returns false if the bounded expansion did not converge (not observed).
bool gamma_tails(int twice_a, double y, GammaTails *out) {
    if (twice_a < 1 || twice_a > kMaxTwiceA || !(y > 0.0)) return false;
    const double a = 0.5 * static_cast<double>(twice_a);
    const double log_pref = log_poisson_term(twice_a, y);  // log( y^a e^-y / Gamma(a+1) )
    const double log_a = std::log(a);
    out->log_yg = log_a + log_pref;
    bool converged = false;
    if (y < a + 1.0) {
        // Series [NR 6.2.5], [AS 6.5.29]:
        //   P(a,y) = y^a e^-y / Gamma(a+1) * sum_{n>=0} y^n / ((a+1)...(a+n)).
        double sum = 1.0;
        double term = 1.0;
        double ap = a;
        for (int n = 0; n < kGammaMaxIter; ++n) {
            ap += 1.0;
            term *= y / ap;
            sum += term;
            if (term <= sum * (0.125 * kEps)) {
                converged = true;
                break;
            }
        }
        out->log_p = log_pref + std::log(sum);
        out->p = std::exp(out->log_p);
        out->q = 1.0 - out->p;
        out->log_q = std::log(out->q);
    } else {
        // Continued fraction [NR 6.2.7] (even part of [AS 6.5.31]), modified Lentz [NR 5.2]:
        //   Q(a,y) = y^a e^-y / Gamma(a) * 1/(y+1-a- 1(1-a)/(y+3-a- 2(2-a)/(y+5-a- ...))).
        double b = y + 1.0 - a;
        double c = 1.0 / kTiny;
        double d = 1.0 / b;
        double h = d;
        for (int i = 1; i <= kGammaMaxIter; ++i) {
            const double di = static_cast<double>(i);
            const double an = -di * (di - a);
            b += 2.0;
            d = an * d + b;
            if (std::fabs(d) < kTiny) d = kTiny;
            c = b + an / c;
            if (std::fabs(c) < kTiny) c = kTiny;
            d = 1.0 / d;
            const double del = d * c;
            h *= del;
            if (std::fabs(del - 1.0) <= kEps) {
                converged = true;
                break;
            }
        }
        // Q = a * (y^a e^-y / Gamma(a+1)) * h
        out->log_q = out->log_yg + std::log(h);
        out->q = std::exp(out->log_q);
        out->p = 1.0 - out->q;
        out->log_p = std::log(out->p);
    }
    return converged;
}

// ---- Argument checks ------------------------------------------------------------------------

bool dof_ok(int dof) {
    return dof >= 1 && dof <= SFD_CHI2_MAX_DOF;
}

// x >= 0 and finite (rejects NaN and +-Inf).
bool x_ok(double x) {
    return x >= 0.0 && x <= std::numeric_limits<double>::max();
}

// ---- Quantile starting point -----------------------------------------------------------------

// Upper standard-normal quantile z with P(Z > z) = alpha, |error| < 4.5e-4 [AS 26.2.23].
// Only a starting point for Newton.
double normal_upper_quantile_approx(double alpha) {
    const double pp = alpha < 0.5 ? alpha : 1.0 - alpha;  // in (0, 0.5]
    const double t = std::sqrt(-2.0 * std::log(pp));
    const double num = 2.515517 + t * (0.802853 + t * 0.010328);
    const double den = 1.0 + t * (1.432788 + t * (0.189269 + t * 0.001308));
    const double z = t - num / den;
    return alpha < 0.5 ? z : -z;
}

// Starting point for the quantile: Wilson-Hilferty [AS 26.4.17]
//   x ~ k (1 - 2/(9k) + z sqrt(2/(9k)))^3,
// raised to the lower bound 2 (p Gamma(a+1))^(1/a), p = 1 - alpha, which follows from
// P(a, y) <= y^a / Gamma(a+1) and is the right asymptote for small p.
double quantile_start(double alpha, int dof) {
    const double k = static_cast<double>(dof);
    const double a = 0.5 * k;
    const double p_lower = 1.0 - alpha;
    double x0 = 0.0;
    if (p_lower > 0.0) {
        x0 = 2.0 * std::exp((std::log(p_lower) + log_gamma_plus_one(dof)) / a);
    }
    const double s = 2.0 / (9.0 * k);
    const double base = 1.0 - s + normal_upper_quantile_approx(alpha) * std::sqrt(s);
    if (base > 0.0) {
        const double x_wh = k * base * base * base;
        if (x_wh > x0) x0 = x_wh;
    }
    if (!(x0 > 1.0e-300)) x0 = 1.0e-300;  // p_lower rounded to 0 or underflow
    return x0;
}

// Quantile solver for 1 <= dof <= SFD_CHI2_MAX_DOF, kAlphaMin < alpha < 1.
// Safeguarded Newton in u = log(x) on h(u) = log(T(x)) - log(t), where the tail T and target t
// are (Q, alpha) for alpha <= 1/2 and (P, 1 - alpha) otherwise (1 - alpha is exact there,
// Sterbenz). Working on log T keeps full relative accuracy for alpha down to 1e-300 and for
// tiny lower quantiles. dh/du = -+ x f(x) / T, with x f(x) = y g(y), so the step is
//   du = +- h * T / (y g(y)),
// a ratio the expansions deliver without under/overflow. log T is concave in u (the
// log-Gamma distribution has a log-concave density), so Newton overshoots at most once;
// a bracket [u_lo, u_hi] and a step cap guard the remaining cases with bisection in u.
sfd_status_t quantile_solve(double alpha, int dof, double *x_out) {
    const bool upper = alpha <= 0.5;
    const double log_target = std::log(upper ? alpha : 1.0 - alpha);
    double u = std::log(quantile_start(alpha, dof));
    double u_lo = 0.0;
    double u_hi = 0.0;
    bool have_lo = false;
    bool have_hi = false;
    for (int it = 0; it < kQuantileMaxIter; ++it) {
        GammaTails t{};
        if (!gamma_tails(dof, 0.5 * std::exp(u), &t)) return SFD_ERR_NUMERIC;
        double h = 0.0;
        double du = 0.0;
        bool too_small = false;  // x below the quantile
        if (upper) {
            h = t.log_q - log_target;  // decreasing in u
            too_small = h > 0.0;
            du = h * std::exp(t.log_q - t.log_yg);
        } else {
            h = t.log_p - log_target;  // increasing in u
            too_small = h < 0.0;
            du = -h * std::exp(t.log_p - t.log_yg);
        }
        if (!(h < 0.0) && !(h > 0.0)) {  // exact hit
            *x_out = std::exp(u);
            return SFD_OK;
        }
        if (too_small) {
            u_lo = u;
            have_lo = true;
        } else {
            u_hi = u;
            have_hi = true;
        }
        if (std::fabs(du) <= kQuantileTolLogX) {  // converged: the last step is O(du^2) exact
            *x_out = std::exp(u + du);
            return SFD_OK;
        }
        if (!std::isfinite(du)) du = too_small ? kQuantileMaxStep : -kQuantileMaxStep;
        if (du > kQuantileMaxStep) du = kQuantileMaxStep;
        if (du < -kQuantileMaxStep) du = -kQuantileMaxStep;
        u += du;
        if (have_lo && have_hi) {
            if (u_hi - u_lo <= kQuantileTolLogX) {  // bracket already narrower than the tolerance
                *x_out = std::exp(0.5 * (u_lo + u_hi));
                return SFD_OK;
            }
            if (!(u > u_lo && u < u_hi)) u = 0.5 * (u_lo + u_hi);  // bisection in log(x)
        }
    }
    return SFD_ERR_NUMERIC;
}

// log of the Poisson weight e^-m m^j / j!, j >= 0, m > 0 [L].
double log_poisson_weight(int j, double m) {
    if (j == 0) return -m;
    return log_poisson_term(2 * j, m);
}

}  // namespace

// ---- Public API ---------------------------------------------------------------------------------

extern "C" sfd_status_t sfd_chi2_cdf(double x, int dof, double *cdf, double *upper) {
    if (!dof_ok(dof) || !x_ok(x)) return SFD_ERR_INVAL;
    double p = 0.0;
    double q = 1.0;
    const double y = 0.5 * x;
    if (y > 0.0) {  // x = 0 (or the smallest subnormal, whose half rounds to 0): P = 0, Q = 1
        GammaTails t{};
        if (!gamma_tails(dof, y, &t)) return SFD_ERR_NUMERIC;
        p = t.p;
        q = t.q;
    }
    if (cdf != nullptr) *cdf = p;
    if (upper != nullptr) *upper = q;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_chi2_quantile_upper(double alpha, int dof, double *x) {
    if (x == nullptr || !dof_ok(dof) || !(alpha > kAlphaMin) || !(alpha < 1.0)) {
        return SFD_ERR_INVAL;
    }
    return quantile_solve(alpha, dof, x);
}

// Poisson mixture [AS 26.4.25]: F(x; k, lambda) = sum_j w_j P(k/2 + j, x/2),
// w_j = e^-m m^j / j!, m = lambda/2. Summed from the mode j0 = floor(m) downward, then upward
// [BK]; each term is exp(log w_j + log P_j) with P_j from the direct expansion (no recurrence,
// so no error build-up and full relative accuracy even where the CDF is tiny). Truncation uses
// geometric bounds on the Poisson tail: below the mode w_{i-1}/w_i = i/m <= j/m, P_i <= 1;
// above it w_{i+1}/w_i = m/(i+1) <= m/(j+1) and P_i <= P_j (P decreases with the shape).
extern "C" sfd_status_t sfd_ncchi2_cdf(double x, int dof, double lambda, double *cdf) {
    if (cdf == nullptr || !dof_ok(dof) || !x_ok(x) || !(lambda >= 0.0) || !(lambda <= kLambdaMax)) {
        return SFD_ERR_INVAL;
    }
    const double y = 0.5 * x;
    if (!(y > 0.0)) {
        *cdf = 0.0;
        return SFD_OK;
    }
    if (!(lambda > 0.0)) {
        GammaTails t{};
        if (!gamma_tails(dof, y, &t)) return SFD_ERR_NUMERIC;
        *cdf = t.p;
        return SFD_OK;
    }
    const double m = 0.5 * lambda;
    const int j0 = static_cast<int>(m);  // mode of the Poisson weights (m >= 0: truncation = floor)
    int terms_left = kNcMaxTerms;

    GammaTails t{};
    if (!gamma_tails(dof + 2 * j0, y, &t)) return SFD_ERR_NUMERIC;
    double sum = std::exp(log_poisson_weight(j0, m) + t.log_p);
    --terms_left;

    // Downward from the mode (at most j0 <= 500 terms).
    for (int step = 1; step < kNcMaxTerms; ++step) {
        const int j = j0 - step;
        if (j < 0 || terms_left <= 0) break;
        if (!gamma_tails(dof + 2 * j, y, &t)) return SFD_ERR_NUMERIC;
        const double log_w = log_poisson_weight(j, m);
        sum += std::exp(log_w + t.log_p);
        --terms_left;
        const double r = static_cast<double>(j) / m;  // < 1 below the mode
        const double rest = std::exp(log_w) * r / (1.0 - r);
        if (rest <= kNcRelTol * sum) break;
    }
    // Upward from the mode.
    for (int step = 1; step < kNcMaxTerms; ++step) {
        if (terms_left <= 0) break;
        const int j = j0 + step;
        if (!gamma_tails(dof + 2 * j, y, &t)) return SFD_ERR_NUMERIC;
        const double log_w = log_poisson_weight(j, m);
        const double term = std::exp(log_w + t.log_p);
        sum += term;
        --terms_left;
        const double r = m / static_cast<double>(j + 1);  // < 1 above the mode
        const double rest = term * r / (1.0 - r);
        if (rest <= kNcRelTol * sum) break;
    }
    if (sum > 1.0) sum = 1.0;
    *cdf = sum;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_chi2_table_init(sfd_chi2_table_t *table, double alpha) {
    if (table == nullptr || !(alpha > kAlphaMin) || !(alpha < 1.0)) return SFD_ERR_INVAL;
    table->alpha = 0.0;  // unusable until every entry is filled
    table->threshold[0] = 0.0;
    for (int k = 1; k <= SFD_CHI2_MAX_DOF; ++k) {
        const sfd_status_t st = sfd_chi2_quantile_upper(alpha, k, &table->threshold[k]);
        if (st != SFD_OK) return st;
    }
    table->alpha = alpha;
    return SFD_OK;
}
