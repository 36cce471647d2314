/* SPDX-License-Identifier: MIT */
/* fuzz.log_reader: the input is a whole log file, read by the tools' one log reader
 * (apps/common/sfd_log_reader.h) in strict and in salvage mode. Oracles, beyond no crash and no
 * sanitizer report:
 *  - every event read lies inside the file, after the previous one, with a channel length of
 *    1..SFD_LOG_MAX_CHANNEL, no NUL in the channel and a data length >= 0 (its bytes are all
 *    read here, so an overread is an ASan report);
 *  - strict mode ends with SFD_LOG_END only when the events tile the file exactly; any other
 *    end is an error status with an offset inside the file and a message naming it;
 *  - salvage mode never ends with a read error on a good file: SFD_LOG_END or SFD_LOG_NO_EVENTS,
 *    and the good events' bytes plus the bytes skipped add up to the file size, with at least
 *    one bad event counted when bytes were skipped;
 *  - the strict events are the first salvage events, bit for bit. */
#define _GNU_SOURCE
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "sfd_log_reader.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FZ_CHECK(cond)                                                                         \
    do {                                                                                       \
        if (!(cond)) {                                                                         \
            fprintf(stderr, "fuzz.log_reader: check failed: %s (line %d)\n", #cond, __LINE__); \
            abort();                                                                           \
        }                                                                                      \
    } while (0)

enum { FZ_MAX_KEPT = 64 };

typedef struct {
    int64_t offset, timestamp;
    int32_t channellen, datalen;
    uint32_t digest;
} fz_event_t;

static sfd_log_reader_t g_reader;
static fz_event_t g_strict[FZ_MAX_KEPT];

static uint32_t digest(const sfd_log_event_t *ev) {
    uint32_t h = 2166136261u;
    for (int32_t i = 0; i < ev->channellen; ++i) h = (h ^ (uint8_t)ev->channel[i]) * 16777619u;
    for (int32_t i = 0; i < ev->datalen; ++i) h = (h ^ ev->data[i]) * 16777619u;
    return h;
}

/* Reads the whole file; returns the final status and checks the per-event oracles. */
static sfd_log_status_t read_all(const char *path, int salvage, int64_t size, int64_t *n_events,
                                 int64_t *event_bytes) {
    sfd_log_status_t st = sfd_log_open(&g_reader, path, salvage);
    *n_events = 0;
    *event_bytes = 0;
    int64_t end_prev = 0;
    sfd_log_event_t ev;
    while (st == SFD_LOG_OK && (st = sfd_log_next(&g_reader, &ev)) == SFD_LOG_OK) {
        FZ_CHECK(ev.channellen >= 1 && ev.channellen <= SFD_LOG_MAX_CHANNEL);
        FZ_CHECK(ev.datalen >= 0);
        FZ_CHECK(ev.offset >= end_prev);
        const int64_t len = SFD_LOG_HEADER_BYTES + (int64_t)ev.channellen + ev.datalen;
        FZ_CHECK(ev.offset + len <= size);
        FZ_CHECK(strlen(ev.channel) == (size_t)ev.channellen);
        if (!salvage) FZ_CHECK(ev.offset == end_prev); /* strict: events tile the file */
        end_prev = ev.offset + len;
        *event_bytes += len;
        const uint32_t d = digest(&ev);
        if (*n_events < FZ_MAX_KEPT) {
            fz_event_t *k = &g_strict[*n_events];
            if (!salvage) {
                k->offset = ev.offset;
                k->timestamp = ev.timestamp;
                k->channellen = ev.channellen;
                k->datalen = ev.datalen;
                k->digest = d;
            }
        }
        ++*n_events;
    }
    if (st != SFD_LOG_END && st != SFD_LOG_OK) {
        FZ_CHECK(g_reader.message[0] != '\0');
        FZ_CHECK(strstr(g_reader.message, path) != NULL);
    }
    if (!salvage && st == SFD_LOG_END) FZ_CHECK(end_prev == size);
    return st;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const int fd = memfd_create("fuzz_log", 0);
    FZ_CHECK(fd >= 0);
    size_t done = 0;
    while (done < size) {
        const ssize_t w = write(fd, data + done, size - done);
        FZ_CHECK(w > 0);
        done += (size_t)w;
    }
    char path[64];
    snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    int64_t n_strict = 0, b_strict = 0, n_salv = 0, b_salv = 0;
    const sfd_log_status_t s1 = read_all(path, 0, (int64_t)size, &n_strict, &b_strict);
    sfd_log_close(&g_reader);
    if (size == 0) FZ_CHECK(s1 == SFD_LOG_NO_EVENTS);
    /* salvage: the strict events first, the byte accounting exact */
    fz_event_t kept[FZ_MAX_KEPT];
    memcpy(kept, g_strict, sizeof kept);
    sfd_log_status_t s2 = sfd_log_open(&g_reader, path, 1);
    int64_t end_prev = 0;
    sfd_log_event_t ev;
    while (s2 == SFD_LOG_OK && (s2 = sfd_log_next(&g_reader, &ev)) == SFD_LOG_OK) {
        const int64_t len = SFD_LOG_HEADER_BYTES + (int64_t)ev.channellen + ev.datalen;
        FZ_CHECK(ev.offset >= end_prev && ev.offset + len <= (int64_t)size);
        if (n_salv < n_strict && n_salv < FZ_MAX_KEPT) {
            const fz_event_t *k = &kept[n_salv];
            FZ_CHECK(k->offset == ev.offset && k->timestamp == ev.timestamp &&
                     k->channellen == ev.channellen && k->datalen == ev.datalen &&
                     k->digest == digest(&ev));
        }
        end_prev = ev.offset + len;
        b_salv += len;
        ++n_salv;
    }
    FZ_CHECK(s2 == SFD_LOG_END || s2 == SFD_LOG_NO_EVENTS);
    FZ_CHECK(n_salv >= n_strict);
    FZ_CHECK(b_salv + g_reader.bytes_skipped == (int64_t)size);
    FZ_CHECK((g_reader.bytes_skipped > 0) == (g_reader.bad_events > 0));
    if (s1 == SFD_LOG_END) FZ_CHECK(g_reader.bad_events == 0 && n_salv == n_strict);
    sfd_log_close(&g_reader);
    close(fd);
    (void)b_strict;
    return 0;
}
