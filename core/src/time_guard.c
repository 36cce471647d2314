/* SPDX-License-Identifier: MIT */
/* The time-glitch policy of one input stream (sfd_time_guard.h). */
#include "sfd/sfd_time_guard.h"

#include <stddef.h>

void sfd_time_guard_params_default(sfd_time_guard_params_t *prm) {
    if (prm == NULL) return;
    prm->horizon_us = 500000;
    prm->resync_messages = 5;
}

sfd_status_t sfd_time_guard_params_validate(const sfd_time_guard_params_t *prm) {
    if (prm == NULL || prm->horizon_us <= 0 || prm->resync_messages < 2 ||
        prm->resync_messages > 1000) {
        return SFD_ERR_INVAL;
    }
    return SFD_OK;
}

sfd_status_t sfd_time_guard_init(sfd_time_guard_t *g, const sfd_time_guard_params_t *prm) {
    if (g == NULL || sfd_time_guard_params_validate(prm) != SFD_OK) return SFD_ERR_INVAL;
    g->prm = *prm;
    sfd_time_guard_reset(g);
    return SFD_OK;
}

void sfd_time_guard_reset(sfd_time_guard_t *g) {
    if (g == NULL) return;
    g->have_ref = 0;
    g->ref_us = 0;
    g->run = 0;
    g->run_last_us = 0;
}

/* b - a > h, for any int64 values and h > 0, without overflow. */
static int later_by_more_than(int64_t a, int64_t b, int64_t h) {
    if (b <= a) return 0;
    return (uint64_t)b - (uint64_t)a > (uint64_t)h;
}

static sfd_time_verdict_t jumped(sfd_time_guard_t *g, int64_t t_us) {
    const int continues = g->run > 0 && t_us > g->run_last_us &&
                          !later_by_more_than(g->run_last_us, t_us, g->prm.horizon_us);
    g->run = continues ? g->run + 1 : 1;
    g->run_last_us = t_us;
    if (g->run < g->prm.resync_messages) return SFD_TIME_JUMP;
    g->have_ref = 1;
    g->ref_us = t_us;
    g->run = 0;
    return SFD_TIME_RESYNC;
}

static sfd_time_verdict_t accept(sfd_time_guard_t *g, int64_t t_us) {
    g->have_ref = 1;
    g->ref_us = t_us;
    g->run = 0;
    return SFD_TIME_ACCEPT;
}

sfd_time_verdict_t sfd_time_guard_check(sfd_time_guard_t *g, int64_t t_us,
                                        const sfd_time_guard_t *other) {
    const int other_ref = other != NULL && other->have_ref;
    if (!g->have_ref && !other_ref) return accept(g, t_us);
    /* the reference below which a message is out of order, and the newest time of both streams
     * above which it is ahead of them */
    const int64_t r = g->have_ref ? g->ref_us : other->ref_us;
    int64_t newest = r;
    if (other_ref && other->ref_us > newest) newest = other->ref_us;
    const int64_t h = g->prm.horizon_us;
    if (later_by_more_than(newest, t_us, h)) return jumped(g, t_us);
    if (t_us > r) return accept(g, t_us);
    if (!g->have_ref) {
        /* only the other stream's time: within H of it either way is in step */
        return later_by_more_than(t_us, r, h) ? jumped(g, t_us) : accept(g, t_us);
    }
    return later_by_more_than(t_us, r, h - 1) ? jumped(g, t_us) : SFD_TIME_ORDER;
}
