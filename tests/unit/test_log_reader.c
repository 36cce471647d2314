/* SPDX-License-Identifier: MIT */
/* unit.log_reader: the one LCM log reader of the tools (apps/common/sfd_log_reader.h) reads
 * exactly what liblcm's lcm_eventlog_read_next_event() reads on good logs written by liblcm, and
 * gives its documented status with the byte offset of the bad event (never a crash, never a
 * silent loss) on: a log truncated at every byte of its last event, a data length of 0x7fffffff
 * (which crashes liblcm's reader), negative and out-of-range lengths, a NUL in a channel name,
 * junk between events, every
 * single-byte corruption of the first events' headers, an empty file, a directory, /etc/passwd,
 * random bytes and a missing file. In salvage mode the good events plus the bytes skipped always
 * account for the whole file.
 * `test_log_reader --compare LOG` compares the reader with liblcm on any log (the integration test
 * node_logplayer runs it on a recording of Debian's lcm-logger). */
#include "sfd_test.h"

#include <lcm/eventlog.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sfd_log_reader.h"

enum { NUM_EVENTS = 7 };

static char g_dir[256];
static uint8_t *g_good; /* the good log's bytes */
static size_t g_good_size;
static int64_t g_offset[NUM_EVENTS + 1]; /* event k starts at g_offset[k]; [NUM_EVENTS]: size */
static const char *const g_channels[NUM_EVENTS] = {
    "IMU",        "CAMERA_INFO", "FEATURES",
    "TRUTH",      "X",           "A_CHANNEL_NAME_OF_THE_LONGEST_LENGTH_LCM_ALLOWS_SIXTY_THREE_BYT",
    "SFD_VERDICT"};
static const int32_t g_datalen[NUM_EVENTS] = {0, 1, 100, 70000, 3, 1000, 17};

static void path_of(char *out, size_t n, const char *name) {
    snprintf(out, n, "%s/%s", g_dir, name);
}

static void write_bytes(const char *path, const uint8_t *p, size_t n) {
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    if (n > 0) assert_int_equal(fwrite(p, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
}

static void put_be32(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

/* A log written by liblcm, read back into g_good. */
static int setup(void **state) {
    (void)state;
    const char *tmp = getenv("TMPDIR");
    snprintf(g_dir, sizeof g_dir, "%s/sfd_log_reader.XXXXXX", tmp != NULL ? tmp : "/tmp");
    if (mkdtemp(g_dir) == NULL) return -1;
    char path[512];
    path_of(path, sizeof path, "good.lcmlog");
    lcm_eventlog_t *log = lcm_eventlog_create(path, "w");
    if (log == NULL) return -1;
    static uint8_t data[70000 + NUM_EVENTS]; /* event k writes data + k */
    uint32_t x = 12345u;
    for (size_t i = 0; i < sizeof data; ++i) {
        x = x * 1664525u + 1013904223u;
        data[i] = (uint8_t)(x >> 24);
    }
    data[50] = 0xED; /* a sync word inside the data must not confuse anyone */
    data[51] = 0xA1;
    data[52] = 0xDA;
    data[53] = 0x01;
    int64_t off = 0;
    for (int k = 0; k < NUM_EVENTS; ++k) {
        lcm_eventlog_event_t ev;
        memset(&ev, 0, sizeof ev);
        ev.timestamp = 1000000 + 1000 * k - (k == 4 ? 5000000 : 0);
        ev.channellen = (int32_t)strlen(g_channels[k]);
        char channel[64];
        snprintf(channel, sizeof channel, "%s", g_channels[k]);
        ev.channel = channel;
        ev.datalen = g_datalen[k];
        ev.data = data + k;
        if (lcm_eventlog_write_event(log, &ev) != 0) return -1;
        g_offset[k] = off;
        off += SFD_LOG_HEADER_BYTES + ev.channellen + ev.datalen;
    }
    g_offset[NUM_EVENTS] = off;
    lcm_eventlog_destroy(log);
    FILE *f = fopen(path, "rb");
    if (f == NULL) return -1;
    g_good = malloc((size_t)off);
    g_good_size = fread(g_good, 1, (size_t)off + 1, f);
    fclose(f);
    return g_good_size == (size_t)off ? 0 : -1;
}

static int teardown(void **state) {
    (void)state;
    static const char *const files[] = {"good", "cut", "len", "junk", "flip", "empty", "random"};
    for (size_t k = 0; k < sizeof files / sizeof files[0]; ++k) {
        char path[512];
        snprintf(path, sizeof path, "%s/%s.lcmlog", g_dir, files[k]);
        unlink(path); /* some may not exist */
    }
    free(g_good);
    return rmdir(g_dir) == 0 ? 0 : -1;
}

/* Reads `path` to the end: the number of good events, their total size, the final status. */
typedef struct {
    int events;
    int64_t bytes; /* of the good events */
    sfd_log_status_t status;
    int64_t error_offset, bad_events, bytes_skipped, offsets[64];
    char message[1536];
} result_t;

static result_t read_all(const char *path, int salvage) {
    result_t res;
    memset(&res, 0, sizeof res);
    static sfd_log_reader_t r;
    sfd_log_status_t s = sfd_log_open(&r, path, salvage);
    sfd_log_event_t ev;
    if (s == SFD_LOG_OK) {
        while ((s = sfd_log_next(&r, &ev)) == SFD_LOG_OK) {
            assert_true(ev.offset >= 0 && ev.offset + SFD_LOG_HEADER_BYTES <= r.size);
            assert_int_equal(strlen(ev.channel), (size_t)ev.channellen);
            if (res.events < 64) res.offsets[res.events] = ev.offset;
            ++res.events;
            res.bytes += SFD_LOG_HEADER_BYTES + ev.channellen + ev.datalen;
        }
    }
    assert_int_equal(sfd_log_next(&r, &ev), s); /* an end or error status stays */
    res.status = s;
    res.error_offset = r.error_offset;
    res.bad_events = r.bad_events;
    res.bytes_skipped = r.bytes_skipped;
    snprintf(res.message, sizeof res.message, "%s", r.message);
    sfd_log_close(&r);
    if (s != SFD_LOG_END) {
        assert_non_null(strstr(res.message, path)); /* every error names the file */
        assert_null(strchr(res.message, '\n'));     /* on one line */
    }
    return res;
}

/* The number of events liblcm's reader returns (after checking that ours returns the same ones,
 * field by field, in the same order). */
static int compare_with_liblcm(const char *path) {
    static sfd_log_reader_t r;
    assert_int_equal(sfd_log_open(&r, path, 0), SFD_LOG_OK);
    lcm_eventlog_t *log = lcm_eventlog_create(path, "r");
    assert_non_null(log);
    int n = 0;
    sfd_log_event_t ev;
    for (lcm_eventlog_event_t *le = lcm_eventlog_read_next_event(log); le != NULL;
         le = lcm_eventlog_read_next_event(log)) {
        assert_int_equal(sfd_log_next(&r, &ev), SFD_LOG_OK);
        assert_int_equal(ev.eventnum, le->eventnum);
        assert_int_equal(ev.timestamp, le->timestamp);
        assert_int_equal(ev.channellen, le->channellen);
        assert_string_equal(ev.channel, le->channel);
        assert_int_equal(ev.datalen, le->datalen);
        assert_memory_equal(ev.data, le->data, (size_t)le->datalen + (le->datalen == 0));
        lcm_eventlog_free_event(le);
        ++n;
    }
    lcm_eventlog_destroy(log);
    sfd_log_close(&r);
    return n;
}

static void good_log_reads_as_liblcm_reads_it(void **state) {
    (void)state;
    char path[512];
    path_of(path, sizeof path, "good.lcmlog");
    assert_int_equal(compare_with_liblcm(path), NUM_EVENTS);
    for (int salvage = 0; salvage < 2; ++salvage) {
        const result_t res = read_all(path, salvage);
        assert_int_equal(res.status, SFD_LOG_END);
        assert_int_equal(res.events, NUM_EVENTS);
        assert_int_equal(res.bytes, (int64_t)g_good_size);
        assert_int_equal(res.bad_events, 0);
        assert_int_equal(res.bytes_skipped, 0);
        for (int k = 0; k < NUM_EVENTS; ++k) assert_int_equal(res.offsets[k], g_offset[k]);
    }
}

/* In salvage mode every byte is either in a good event or counted as skipped. */
static void assert_salvage_accounts(const result_t *res, int64_t size) {
    assert_int_equal(res->bytes + res->bytes_skipped, size);
    assert_true((res->bad_events == 0) == (res->bytes_skipped == 0));
}

static void truncated_at_every_byte_of_the_last_event(void **state) {
    (void)state;
    char path[512];
    path_of(path, sizeof path, "cut.lcmlog");
    const int64_t last = g_offset[NUM_EVENTS - 1];
    for (int64_t cut = last; cut < (int64_t)g_good_size; ++cut) {
        write_bytes(path, g_good, (size_t)cut);
        const result_t strict = read_all(path, 0);
        assert_int_equal(strict.events, NUM_EVENTS - 1);
        if (cut == last) { /* a shorter good log */
            assert_int_equal(strict.status, SFD_LOG_END);
        } else {
            assert_int_equal(strict.status, SFD_LOG_TRUNCATED);
            assert_int_equal(strict.error_offset, last);
            char at[64];
            snprintf(at, sizeof at, "truncated event at byte %lld", (long long)last);
            assert_non_null(strstr(strict.message, at));
        }
        const result_t salvage = read_all(path, 1);
        assert_int_equal(salvage.status, SFD_LOG_END);
        assert_int_equal(salvage.events, NUM_EVENTS - 1);
        assert_int_equal(salvage.bad_events, cut > last ? 1 : 0);
        assert_int_equal(salvage.bytes_skipped, cut - last);
        assert_salvage_accounts(&salvage, cut);
        /* liblcm returns the same good events */
        assert_int_equal(compare_with_liblcm(path), NUM_EVENTS - 1);
    }
}

/* The log with the 32-bit field at `field` (header offset) of event k set to v. */
static void write_with_field(const char *path, int k, int field, uint32_t v) {
    uint8_t *copy = malloc(g_good_size);
    assert_non_null(copy);
    memcpy(copy, g_good, g_good_size);
    put_be32(copy + g_offset[k] + field, v);
    write_bytes(path, copy, g_good_size);
    free(copy);
}

static void bad_lengths_give_their_status_and_offset(void **state) {
    (void)state;
    char path[512];
    path_of(path, sizeof path, "len.lcmlog");
    static const struct {
        int field; /* 20: channel length, 24: data length */
        uint32_t value;
        sfd_log_status_t status;
    } cases[] = {
        {24, 0x7fffffffu, SFD_LOG_TRUNCATED}, /* liblcm's reader crashes on this one */
        {24, 0x7ffffff0u, SFD_LOG_TRUNCATED},  {24, 0xffffffffu, SFD_LOG_BAD_LENGTH},
        {24, 0x80000000u, SFD_LOG_BAD_LENGTH}, {20, 0, SFD_LOG_BAD_LENGTH},
        {20, 0xfffffffbu, SFD_LOG_BAD_LENGTH}, {20, 1000, SFD_LOG_BAD_LENGTH},
        {20, 0x7fffffffu, SFD_LOG_BAD_LENGTH}, {24, 200000, SFD_LOG_TRUNCATED},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        for (int k = 1; k < NUM_EVENTS; k += NUM_EVENTS - 2) { /* a middle and the last event */
            write_with_field(path, k, cases[c].field, cases[c].value);
            const result_t strict = read_all(path, 0);
            assert_int_equal(strict.status, cases[c].status);
            assert_int_equal(strict.events, k);
            assert_int_equal(strict.error_offset, g_offset[k]);
            const result_t salvage = read_all(path, 1);
            assert_int_equal(salvage.status, SFD_LOG_END);
            assert_int_equal(salvage.events, NUM_EVENTS - 1); /* every other event recovered */
            assert_int_equal(salvage.bad_events, 1);
            assert_int_equal(salvage.bytes_skipped, g_offset[k + 1] - g_offset[k]);
            assert_salvage_accounts(&salvage, (int64_t)g_good_size);
        }
    }
    write_with_field(path, 1, 24, 0x7fffffffu);
    result_t r = read_all(path, 0);
    assert_non_null(strstr(r.message, "data 2147483647 bytes"));
    /* a NUL byte in a channel name */
    uint8_t *copy = malloc(g_good_size);
    assert_non_null(copy);
    memcpy(copy, g_good, g_good_size);
    copy[g_offset[2] + SFD_LOG_HEADER_BYTES + 1] = 0;
    write_bytes(path, copy, g_good_size);
    free(copy);
    r = read_all(path, 0);
    assert_int_equal(r.status, SFD_LOG_BAD_CHANNEL);
    assert_int_equal(r.error_offset, g_offset[2]);
    r = read_all(path, 1);
    assert_int_equal(r.events, NUM_EVENTS - 1);
    assert_int_equal(r.bytes_skipped, g_offset[3] - g_offset[2]);
}

static void junk_between_events(void **state) {
    (void)state;
    char path[512];
    path_of(path, sizeof path, "junk.lcmlog");
    /* plain junk, and junk holding a sync word whose header is bad */
    static const uint8_t junk1[] = {'g', 'a', 'r', 'b', 'a', 'g', 'e'};
    static const uint8_t junk2[] = {0xED, 0xA1, 0xDA, 0x01, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff,
                                    0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff,
                                    0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xED, 0xA1};
    const uint8_t *junks[2] = {junk1, junk2};
    const size_t junk_len[2] = {sizeof junk1, sizeof junk2};
    for (int j = 0; j < 2; ++j) {
        for (int k = 1; k <= NUM_EVENTS; ++k) { /* before event k (k == NUM_EVENTS: at the end) */
            const size_t n = g_good_size + junk_len[j];
            uint8_t *buf = malloc(n);
            assert_non_null(buf);
            memcpy(buf, g_good, (size_t)g_offset[k]);
            memcpy(buf + g_offset[k], junks[j], junk_len[j]);
            memcpy(buf + g_offset[k] + junk_len[j], g_good + g_offset[k],
                   g_good_size - (size_t)g_offset[k]);
            write_bytes(path, buf, n);
            free(buf);
            const result_t strict = read_all(path, 0);
            assert_int_equal(strict.events, k);
            assert_int_equal(strict.error_offset, g_offset[k]);
            assert_true(strict.status == SFD_LOG_BAD_SYNC || strict.status == SFD_LOG_BAD_LENGTH ||
                        strict.status == SFD_LOG_TRUNCATED);
            if (j == 0) assert_int_equal(strict.status, SFD_LOG_BAD_SYNC);
            const result_t salvage = read_all(path, 1);
            assert_int_equal(salvage.status, SFD_LOG_END);
            assert_int_equal(salvage.events, NUM_EVENTS);
            assert_int_equal(salvage.bad_events, 1);
            assert_int_equal(salvage.bytes_skipped, (int64_t)junk_len[j]);
            assert_salvage_accounts(&salvage, (int64_t)n);
        }
    }
}

/* Every byte of the first three events' headers set to 0x00, 0x80 and 0xff: a documented status,
 * never a crash, and salvage accounts for every byte. */
static void every_header_byte_corrupted(void **state) {
    (void)state;
    char path[512];
    path_of(path, sizeof path, "flip.lcmlog");
    uint8_t *copy = malloc(g_good_size);
    assert_non_null(copy);
    static const uint8_t values[3] = {0x00, 0x80, 0xff};
    for (int k = 0; k < 3; ++k) {
        for (int b = 0; b < SFD_LOG_HEADER_BYTES; ++b) {
            for (int v = 0; v < 3; ++v) {
                memcpy(copy, g_good, g_good_size);
                copy[g_offset[k] + b] = values[v];
                write_bytes(path, copy, g_good_size);
                const result_t strict = read_all(path, 0);
                assert_true((strict.status >= SFD_LOG_END && strict.status <= SFD_LOG_TRUNCATED) ||
                            strict.status == SFD_LOG_BAD_CHANNEL);
                assert_true(strict.events <= NUM_EVENTS);
                if (strict.status != SFD_LOG_END) {
                    assert_true(strict.error_offset >= g_offset[k] &&
                                strict.error_offset < (int64_t)g_good_size);
                }
                /* a corrupt length may shift what follows: salvage still accounts for it all */
                const result_t salvage = read_all(path, 1);
                assert_true(salvage.status == SFD_LOG_END);
                assert_true(salvage.events >= k && salvage.events <= NUM_EVENTS);
                assert_salvage_accounts(&salvage, (int64_t)g_good_size);
            }
        }
    }
    free(copy);
}

static void not_logs(void **state) {
    (void)state;
    char path[512];
    path_of(path, sizeof path, "empty.lcmlog");
    write_bytes(path, g_good, 0);
    for (int salvage = 0; salvage < 2; ++salvage) {
        result_t res = read_all(path, salvage);
        assert_int_equal(res.status, SFD_LOG_NO_EVENTS);
        assert_non_null(strstr(res.message, "empty file"));
        res = read_all(g_dir, salvage);
        assert_int_equal(res.status, SFD_LOG_NOT_FILE);
        assert_non_null(strstr(res.message, "is a directory"));
        path_of(path, sizeof path, "missing.lcmlog");
        res = read_all(path, salvage);
        assert_int_equal(res.status, SFD_LOG_OPEN_FAILED);
        path_of(path, sizeof path, "empty.lcmlog");
    }
    struct stat st;
    if (stat("/etc/passwd", &st) == 0 && st.st_size > 0) {
        result_t res = read_all("/etc/passwd", 0);
        assert_int_equal(res.status, SFD_LOG_BAD_SYNC);
        assert_int_equal(res.error_offset, 0);
        assert_non_null(strstr(res.message, "no sync word at byte 0"));
        res = read_all("/etc/passwd", 1);
        assert_int_equal(res.status, SFD_LOG_NO_EVENTS);
        assert_int_equal(res.bytes_skipped, (int64_t)st.st_size);
    }
    /* random bytes, with and without sync words sprinkled in */
    path_of(path, sizeof path, "random.lcmlog");
    static uint8_t rnd[100000];
    uint32_t x = 7u;
    for (int round = 0; round < 2; ++round) {
        for (size_t i = 0; i < sizeof rnd; ++i) {
            x = x * 1664525u + 1013904223u;
            rnd[i] = (uint8_t)(x >> 24);
            if (round == 1 && i % 997 == 0 && i + 4 < sizeof rnd) put_be32(rnd + i, SFD_LOG_SYNC);
        }
        rnd[0] = 0x00;
        write_bytes(path, rnd, sizeof rnd);
        const result_t strict = read_all(path, 0);
        assert_int_equal(strict.status, SFD_LOG_BAD_SYNC);
        assert_int_equal(strict.error_offset, 0);
        const result_t salvage = read_all(path, 1);
        assert_true(salvage.status == SFD_LOG_END || salvage.status == SFD_LOG_NO_EVENTS);
        assert_int_equal(salvage.bytes + salvage.bytes_skipped, (int64_t)sizeof rnd);
    }
}

/* --compare LOG: the reader against liblcm on any log. */
static const char *g_compare_path;
static void compare_file(void **state) {
    (void)state;
    const int n = compare_with_liblcm(g_compare_path);
    const result_t res = read_all(g_compare_path, 0);
    assert_int_equal(res.status, SFD_LOG_END);
    assert_int_equal(res.events, n);
    printf("%s: %d events, read identically by liblcm and sfd_log_reader\n", g_compare_path, n);
}

int main(int argc, char **argv) {
    if (argc == 3 && !strcmp(argv[1], "--compare")) {
        g_compare_path = argv[2];
        const struct CMUnitTest one[] = {cmocka_unit_test(compare_file)};
        return cmocka_run_group_tests(one, NULL, NULL);
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(good_log_reads_as_liblcm_reads_it),
        cmocka_unit_test(truncated_at_every_byte_of_the_last_event),
        cmocka_unit_test(bad_lengths_give_their_status_and_offset),
        cmocka_unit_test(junk_between_events),
        cmocka_unit_test(every_header_byte_corrupted),
        cmocka_unit_test(not_logs),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
