/* SPDX-License-Identifier: MIT */
/* The one bounded reader of LCM log files (sfd_log_reader.h). */
#include "sfd_log_reader.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static uint32_t get_be32(const uint8_t *p) {
    return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | (uint32_t)p[3];
}

static int64_t get_be64(const uint8_t *p) {
    return (int64_t)(((uint64_t)get_be32(p) << 32) | (uint64_t)get_be32(p + 4));
}

const char *sfd_log_status_str(sfd_log_status_t s) {
    switch (s) {
        case SFD_LOG_OK:
            return "ok";
        case SFD_LOG_END:
            return "end of log";
        case SFD_LOG_OPEN_FAILED:
            return "cannot open";
        case SFD_LOG_NOT_FILE:
            return "not a regular file";
        case SFD_LOG_NO_EVENTS:
            return "no LCM event";
        case SFD_LOG_BAD_SYNC:
            return "no sync word";
        case SFD_LOG_BAD_LENGTH:
            return "bad length";
        case SFD_LOG_TRUNCATED:
            return "truncated event";
        case SFD_LOG_IO_ERROR:
            return "read error";
        case SFD_LOG_NO_MEMORY:
            return "out of memory";
        case SFD_LOG_BAD_CHANNEL:
            return "bad channel name";
    }
    return "unknown status";
}

/* Records an error status with its message "PATH: <what>". */
static sfd_log_status_t fail(sfd_log_reader_t *r, sfd_log_status_t s, int64_t offset,
                             const char *what) {
    r->status = s;
    r->error_offset = offset;
    snprintf(r->message, sizeof r->message, "%s: %s", r->path, what);
    return s;
}

static int refresh_size(sfd_log_reader_t *r) {
    struct stat st;
    if (fstat(fileno(r->f), &st) != 0) return -1;
    r->size = (int64_t)st.st_size;
    return 0;
}

typedef struct {
    int64_t eventnum, timestamp;
    int32_t channellen, datalen;
} header_t;

/* Checks the event that would start at `pos` (header in `h` when SFD_LOG_OK); `why` gets the
 * reason of any other status. */
static sfd_log_status_t probe(sfd_log_reader_t *r, int64_t pos, header_t *h, char *why,
                              size_t why_len) {
    static const uint8_t sync[4] = {0xED, 0xA1, 0xDA, 0x01};
    int64_t left = r->size - pos;
    if (left < SFD_LOG_HEADER_BYTES) {
        if (refresh_size(r) != 0) return SFD_LOG_IO_ERROR;
        left = r->size - pos;
    }
    const size_t n = left < SFD_LOG_HEADER_BYTES ? (size_t)left : SFD_LOG_HEADER_BYTES;
    uint8_t hdr[SFD_LOG_HEADER_BYTES];
    if (fseeko(r->f, (off_t)pos, SEEK_SET) != 0 || fread(hdr, 1, n, r->f) != n) {
        snprintf(why, why_len, "read error at byte %lld", (long long)pos);
        return SFD_LOG_IO_ERROR;
    }
    if (memcmp(hdr, sync, n < 4 ? n : 4) != 0) {
        snprintf(why, why_len, "no sync word at byte %lld (found", (long long)pos);
        for (size_t k = 0; k < (n < 4 ? n : 4); ++k) {
            const size_t used = strlen(why);
            snprintf(why + used, why_len - used, " %02x", hdr[k]);
        }
        const size_t used = strlen(why);
        snprintf(why + used, why_len - used, "%s)", n < 4 ? " at the end of the file" : "");
        return SFD_LOG_BAD_SYNC;
    }
    if (n < SFD_LOG_HEADER_BYTES) {
        snprintf(why, why_len, "truncated event at byte %lld (header needs %d bytes, %lld left)",
                 (long long)pos, SFD_LOG_HEADER_BYTES, (long long)left);
        return SFD_LOG_TRUNCATED;
    }
    h->eventnum = get_be64(hdr + 4);
    h->timestamp = get_be64(hdr + 12);
    h->channellen = (int32_t)get_be32(hdr + 20);
    h->datalen = (int32_t)get_be32(hdr + 24);
    if (h->channellen < 1 || h->channellen > SFD_LOG_MAX_CHANNEL || h->datalen < 0) {
        snprintf(why, why_len, "bad length in event at byte %lld (channel %ld, data %ld)",
                 (long long)pos, (long)h->channellen, (long)h->datalen);
        return SFD_LOG_BAD_LENGTH;
    }
    const int64_t need = SFD_LOG_HEADER_BYTES + (int64_t)h->channellen + (int64_t)h->datalen;
    if (need > left) {
        if (refresh_size(r) != 0) return SFD_LOG_IO_ERROR;
        left = r->size - pos;
    }
    if (need > left) {
        snprintf(why, why_len,
                 "truncated event at byte %lld (channel %ld + data %ld bytes, %lld left in the "
                 "file)",
                 (long long)pos, (long)h->channellen, (long)h->datalen,
                 (long long)(left - SFD_LOG_HEADER_BYTES));
        return SFD_LOG_TRUNCATED;
    }
    if (fread(r->channel, 1, (size_t)h->channellen, r->f) != (size_t)h->channellen) {
        snprintf(why, why_len, "read error in the event at byte %lld", (long long)pos);
        return SFD_LOG_IO_ERROR;
    }
    if (memchr(r->channel, 0, (size_t)h->channellen) != NULL) {
        snprintf(why, why_len, "bad channel name in event at byte %lld (holds a NUL byte)",
                 (long long)pos);
        return SFD_LOG_BAD_CHANNEL;
    }
    r->channel[h->channellen] = '\0';
    return SFD_LOG_OK;
}

sfd_log_status_t sfd_log_open(sfd_log_reader_t *r, const char *path, int salvage) {
    memset(r, 0, sizeof *r);
    r->salvage = salvage != 0;
    snprintf(r->path, sizeof r->path, "%s", path);
    char what[256];
    r->f = fopen(path, "rb");
    if (r->f == NULL) {
        snprintf(what, sizeof what, "cannot open for reading (%s)", strerror(errno));
        return fail(r, SFD_LOG_OPEN_FAILED, 0, what);
    }
    struct stat st;
    if (fstat(fileno(r->f), &st) != 0) {
        snprintf(what, sizeof what, "cannot stat (%s)", strerror(errno));
        return fail(r, SFD_LOG_IO_ERROR, 0, what);
    }
    if (!S_ISREG(st.st_mode)) {
        return fail(r, SFD_LOG_NOT_FILE, 0,
                    S_ISDIR(st.st_mode) ? "is a directory, not an LCM log"
                                        : "not a regular file, not an LCM log");
    }
    r->size = (int64_t)st.st_size;
    return SFD_LOG_OK;
}

/* The end of the file: SFD_LOG_END after a good event, else SFD_LOG_NO_EVENTS. */
static sfd_log_status_t at_end(sfd_log_reader_t *r) {
    if (r->events > 0) return r->status = SFD_LOG_END;
    char what[160];
    if (r->bytes_skipped == 0) {
        snprintf(what, sizeof what, "empty file, not an LCM log");
    } else {
        snprintf(what, sizeof what, "no LCM event in %lld bytes, not an LCM log",
                 (long long)r->bytes_skipped);
    }
    return fail(r, SFD_LOG_NO_EVENTS, 0, what);
}

/* Salvage: the next position after the bad event at `bad` where a good event starts, or -1. */
static int64_t resync(sfd_log_reader_t *r, int64_t bad, sfd_log_status_t *io) {
    uint8_t buf[65536];
    char why[256];
    header_t h;
    int64_t p = bad + 1;
    *io = SFD_LOG_OK;
    for (;;) {
        if (p + 4 > r->size) {
            if (refresh_size(r) != 0) {
                *io = SFD_LOG_IO_ERROR;
                return -1;
            }
            if (p + 4 > r->size) return -1;
        }
        const int64_t want = r->size - p < (int64_t)sizeof buf ? r->size - p : (int64_t)sizeof buf;
        if (fseeko(r->f, (off_t)p, SEEK_SET) != 0 ||
            fread(buf, 1, (size_t)want, r->f) != (size_t)want) {
            *io = SFD_LOG_IO_ERROR;
            return -1;
        }
        for (int64_t i = 0; i + 4 <= want; ++i) {
            if (buf[i] != 0xED || get_be32(buf + i) != SFD_LOG_SYNC) continue;
            const sfd_log_status_t s = probe(r, p + i, &h, why, sizeof why);
            if (s == SFD_LOG_OK) return p + i;
            if (s == SFD_LOG_IO_ERROR) {
                *io = s;
                return -1;
            }
        }
        p += want - 3; /* a sync word may straddle two reads */
    }
}

sfd_log_status_t sfd_log_next(sfd_log_reader_t *r, sfd_log_event_t *ev) {
    if (r->status != SFD_LOG_OK) return r->status;
    if (r->f == NULL) return fail(r, SFD_LOG_IO_ERROR, 0, "not open");
    if (r->offset >= r->size) {
        if (refresh_size(r) != 0) return fail(r, SFD_LOG_IO_ERROR, r->offset, "cannot stat");
        if (r->offset >= r->size) return at_end(r);
    }
    char why[256];
    header_t h;
    const int64_t start = r->offset;
    sfd_log_status_t s = probe(r, start, &h, why, sizeof why);
    int64_t at = start;
    if (s != SFD_LOG_OK && s != SFD_LOG_IO_ERROR && r->salvage) {
        sfd_log_status_t io;
        const int64_t next = resync(r, start, &io);
        if (io != SFD_LOG_OK) return fail(r, io, start, "read error while resynchronizing");
        ++r->bad_events;
        if (next < 0) {
            r->bytes_skipped += r->size - start;
            r->offset = r->size;
            return at_end(r);
        }
        r->bytes_skipped += next - start;
        at = next;
        s = probe(r, at, &h, why, sizeof why);
    }
    if (s != SFD_LOG_OK) return fail(r, s, at, why);
    /* The event lies inside the file: the buffer is at most the file size. */
    if ((size_t)h.datalen + 1 > r->data_capacity) {
        uint8_t *d = (uint8_t *)realloc(r->data, (size_t)h.datalen + 1);
        if (d == NULL) {
            snprintf(why, sizeof why, "cannot allocate %ld bytes for the event at byte %lld",
                     (long)h.datalen, (long long)at);
            return fail(r, SFD_LOG_NO_MEMORY, at, why);
        }
        r->data = d;
        r->data_capacity = (size_t)h.datalen + 1;
    }
    /* probe() left the file at the data, the channel in r->channel */
    if (fread(r->data, 1, (size_t)h.datalen, r->f) != (size_t)h.datalen) {
        snprintf(why, sizeof why, "read error in the event at byte %lld", (long long)at);
        return fail(r, SFD_LOG_IO_ERROR, at, why);
    }
    r->data[h.datalen] = 0;
    r->offset = at + SFD_LOG_HEADER_BYTES + h.channellen + h.datalen;
    ++r->events;
    ev->offset = at;
    ev->eventnum = h.eventnum;
    ev->timestamp = h.timestamp;
    ev->channellen = h.channellen;
    ev->datalen = h.datalen;
    ev->channel = r->channel;
    ev->data = r->data;
    return SFD_LOG_OK;
}

void sfd_log_close(sfd_log_reader_t *r) {
    if (r->f != NULL) fclose(r->f);
    free(r->data);
    r->f = NULL;
    r->data = NULL;
    r->data_capacity = 0;
}
