/* SPDX-License-Identifier: MIT */
/* The one reader of LCM log files of every sfd tool (sfd-replay, sfd-hil --log, sfd-fuzz-seeds).
 *
 * LCM's log format (each event, all integers big-endian):
 *   uint32 sync word 0xEDA1DA01, int64 event number, int64 timestamp (us),
 *   int32 channel length, int32 data length, channel bytes, data bytes.
 * liblcm's lcm_eventlog_read_next_event() trusts the data length (0x7fffffff makes it crash), and
 * on a bad event it returns NULL as at the end of the file (Debian's liblcm also drops the good
 * event before junk), so its caller cannot tell a corrupt log from a short one. This reader
 * instead checks every event before it allocates anything:
 *   - the sync word must start exactly where the previous event ended (byte 0 for the first);
 *   - the channel length must be 1..SFD_LOG_MAX_CHANNEL, the data length >= 0, and the channel
 *     name must hold no NUL byte;
 *   - the whole event (header, channel, data) must lie inside the file (its size from fstat, read
 *     again when an event seems to run past it, so a log that is still growing is read whole);
 * so the data buffer it allocates is never larger than the file. The event number is not checked
 * (liblcm does not either: split or concatenated logs restart it).
 *
 * Strict mode (salvage 0): the first bad event ends the reading with its status and byte offset.
 * Salvage mode: a bad event is skipped by looking for the next sync word whose event passes the
 * checks above; each skip counts one bad event and the bytes skipped (to the next good event or
 * the end of the file), so nothing is lost silently.
 * A file with no good event at all (empty, or nothing but bad bytes) is SFD_LOG_NO_EVENTS. */
#ifndef SFD_LOG_READER_H
#define SFD_LOG_READER_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define SFD_LOG_SYNC 0xEDA1DA01u
#define SFD_LOG_HEADER_BYTES 28
/* liblcm's own reader asserts channel lengths below 1000; LCM channels are at most 63 bytes. */
#define SFD_LOG_MAX_CHANNEL 999

typedef enum {
    SFD_LOG_OK = 0,          /* an event was read */
    SFD_LOG_END = 1,         /* the end of the file after at least one good event */
    SFD_LOG_OPEN_FAILED = 2, /* the file cannot be opened (errno in the message) */
    SFD_LOG_NOT_FILE = 3,    /* a directory or another file that is not a regular file */
    SFD_LOG_NO_EVENTS = 4,   /* an empty file, or (--salvage) one without any good event */
    SFD_LOG_BAD_SYNC = 5,    /* no sync word where an event must start */
    SFD_LOG_BAD_LENGTH = 6,  /* channel length outside 1..SFD_LOG_MAX_CHANNEL or data length < 0 */
    SFD_LOG_TRUNCATED = 7,   /* the event runs past the end of the file */
    SFD_LOG_IO_ERROR = 8,    /* a read failed */
    SFD_LOG_NO_MEMORY = 9,   /* the data buffer (at most the file size) cannot be allocated */
    SFD_LOG_BAD_CHANNEL = 10 /* the channel name holds a NUL byte */
} sfd_log_status_t;

typedef struct {
    int64_t offset; /* byte offset of the event's sync word */
    int64_t eventnum;
    int64_t timestamp;
    int32_t channellen;
    int32_t datalen;
    const char *channel; /* NUL-terminated; valid until the next sfd_log_next() */
    const uint8_t *data; /* datalen bytes; valid until the next sfd_log_next() */
} sfd_log_event_t;

typedef struct {
    FILE *f;
    int salvage;
    int64_t size;   /* file size */
    int64_t offset; /* where the next event starts */
    int64_t events; /* good events read */
    int64_t bad_events;
    int64_t bytes_skipped;
    sfd_log_status_t status; /* of the last call */
    int64_t error_offset;    /* byte offset of the bad event of an error status */
    char path[1024];         /* as given (for the messages) */
    char message[1536];      /* "PATH: reason at byte N" of the last error status */
    char channel[SFD_LOG_MAX_CHANNEL + 1];
    uint8_t *data;
    size_t data_capacity;
} sfd_log_reader_t;

/* Opens `path` (SFD_LOG_OK, or an error status with its message). sfd_log_close() is needed
 * whatever it returns. */
sfd_log_status_t sfd_log_open(sfd_log_reader_t *r, const char *path, int salvage);

/* The next good event (SFD_LOG_OK), SFD_LOG_END, or an error status (message in r->message, the
 * bad event's byte offset in r->error_offset). After an error status it returns the same again. */
sfd_log_status_t sfd_log_next(sfd_log_reader_t *r, sfd_log_event_t *ev);

void sfd_log_close(sfd_log_reader_t *r);

/* A short name of a status ("truncated event", ...). */
const char *sfd_log_status_str(sfd_log_status_t s);

#ifdef __cplusplus
}
#endif

#endif /* SFD_LOG_READER_H */
