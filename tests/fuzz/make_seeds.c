/* SPDX-License-Identifier: MIT */
/* sfd-fuzz-seeds LOG.lcmlog OUTDIR: the seed corpus of the fuzz targets, from an sfd-sim log read
 * with the tools' one bounded LCM log reader (apps/common/sfd_log_reader.h; a corrupt log is exit
 * 2 naming the file and the bad event's offset):
 *   OUTDIR/imu, camera_info, features: each event's payload on that channel, one file each;
 *   OUTDIR/sequence: the whole log in fuzz_sequence.c's format (wire FEATURES; compact FEATURES;
 *                    under a few configuration bytes; after an IMU burst that overflows the
 *                    ring), and prefixes of it;
 * plus hand-made edge inputs in each directory: empty, one byte, the fingerprint alone, truncated
 * messages, another channel's message; and the fuzzers' dictionaries in OUTDIR/dicts (see
 * write_dicts). Exit 0 ok, 2 bad usage or unreadable log, 1 write error. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fuzz_harness.h"
#include "sfd_log_reader.h"

enum { MAX_EVENTS = 4096, SEQ_CAP = 4 * 1024 * 1024 };

typedef struct {
    uint8_t *data;
    int32_t size;
    int kind; /* FZ_SEQ_IMU, FZ_SEQ_CAMERA_INFO, FZ_SEQ_FEATURES */
} event_t;

static event_t g_events[MAX_EVENTS];
static int g_num_events;
static uint8_t g_seq[SEQ_CAP];
static sfd_feature_frame_t g_ff;
static int g_failed;

static void write_file(const char *dir, const char *sub, const char *name, const void *data,
                       size_t size) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s/%s", dir, sub, name);
    FILE *f = fopen(path, "wb");
    if (f == NULL || (size > 0 && fwrite(data, 1, size, f) != size) || fclose(f) != 0) {
        fprintf(stderr, "sfd-fuzz-seeds: cannot write %s\n", path);
        g_failed = 1;
    }
}

static void make_dir(const char *dir, const char *sub) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, sub);
    if (mkdir(path, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "sfd-fuzz-seeds: cannot create %s\n", path);
        g_failed = 1;
    }
}

static void put_le(uint8_t *p, const void *v, size_t n) {
    memcpy(p, v, n); /* the targets read host order; the host is little-endian x86-64/aarch64 */
}

/* Appends one record; returns the new length (unchanged if it does not fit). */
static size_t append(size_t len, int kind, const uint8_t *payload, size_t n) {
    if (n > 0xffff || len + FZ_SEQ_HEADER + n > SEQ_CAP) return len;
    g_seq[len] = (uint8_t)kind;
    g_seq[len + 1] = (uint8_t)(n & 0xff);
    g_seq[len + 2] = (uint8_t)(n >> 8);
    if (n > 0) memcpy(&g_seq[len + 3], payload, n);
    return len + FZ_SEQ_HEADER + n;
}

/* The compact payload of a wire FEATURES message (0 if it does not decode). */
static size_t compact_of(const event_t *e, uint8_t *out, size_t cap) {
    if (sfd_feature_frame_t_decode(e->data, 0, e->size, &g_ff) < 0) return 0;
    const int n = g_ff.num_features < 0                              ? 0
                  : g_ff.num_features > SFD_FEATURE_FRAME_T_CAPACITY ? SFD_FEATURE_FRAME_T_CAPACITY
                                                                     : g_ff.num_features;
    const size_t size = FZ_COMPACT_HEADER + (size_t)n * FZ_COMPACT_FEATURE;
    if (size > cap) return 0;
    put_le(out, &g_ff.utime, 8);
    put_le(out + 8, &g_ff.camera_id, 4);
    put_le(out + 12, &g_ff.num_features, 4);
    for (int i = 0; i < n; ++i) {
        uint8_t *p = out + FZ_COMPACT_HEADER + (size_t)i * FZ_COMPACT_FEATURE;
        put_le(p, &g_ff.track_id[i], 8);
        put_le(p + 8, &g_ff.u[i], 8);
        put_le(p + 16, &g_ff.v[i], 8);
        put_le(p + 24, &g_ff.depth[i], 8);
        put_le(p + 32, &g_ff.depth_var[i], 8);
    }
    return size;
}

/* An IMU burst record at rest: @p count samples every 5 ms, the last at 0.995 s (before sfd-sim's
 * first sample at 1 s), which overflows the ring when count > SFD_IMU_RING_CAPACITY. */
static size_t append_burst(size_t len, uint16_t count) {
    uint8_t p[FZ_BURST_SIZE];
    memset(p, 0, sizeof p);
    const int64_t t0 = 995000 - 5000 * (int64_t)(count - 1);
    const int32_t step = 5000;
    const double g = 9.81;
    put_le(p, &t0, 8);
    put_le(p + 8, &step, 4);
    put_le(p + 12, &count, 2);
    put_le(p + 38 + 16, &g, 8); /* accel z */
    return append(len, FZ_SEQ_IMU_BURST, p, sizeof p);
}

/* The first @p max_events events as a sequence input (compact FEATURES if @p compact), after an
 * IMU burst of @p burst samples if > 0. */
static size_t sequence_of(uint8_t config, int compact, int max_events, uint16_t burst) {
    static uint8_t buf[FZ_COMPACT_HEADER + SFD_FEATURE_FRAME_T_CAPACITY * FZ_COMPACT_FEATURE];
    size_t len = 0;
    g_seq[len++] = config;
    if (burst > 0) len = append_burst(len, burst);
    for (int i = 0; i < g_num_events && i < max_events; ++i) {
        const event_t *e = &g_events[i];
        if (compact && e->kind == FZ_SEQ_FEATURES) {
            const size_t n = compact_of(e, buf, sizeof buf);
            if (n > 0) {
                len = append(len, FZ_SEQ_FEATURES_COMPACT, buf, n);
                continue;
            }
        }
        len = append(len, e->kind, e->data, (size_t)e->size);
    }
    return len;
}

/* Edge inputs of a channel, from one of its messages (@p e may be NULL) and another channel's. */
static void edges(const char *dir, const char *sub, const event_t *e, const event_t *other) {
    const uint8_t one = 0x5a;
    write_file(dir, sub, "edge_empty", &one, 0);
    write_file(dir, sub, "edge_one_byte", &one, 1);
    if (e != NULL && e->size >= 8) {
        write_file(dir, sub, "edge_fingerprint_only", e->data, 8);
        write_file(dir, sub, "edge_truncated_half", e->data, (size_t)e->size / 2);
        write_file(dir, sub, "edge_truncated_last_byte", e->data, (size_t)e->size - 1);
    }
    if (other != NULL) write_file(dir, sub, "edge_other_channel", other->data, (size_t)other->size);
}

/* One libFuzzer dictionary entry: "..." with every byte outside printable ASCII (and " and \)
 * as \xNN. */
static void dict_entry(FILE *f, const uint8_t *b, size_t n) {
    fputc('"', f);
    for (size_t i = 0; i < n; ++i) {
        if (b[i] >= 0x20 && b[i] < 0x7f && b[i] != '"' && b[i] != '\\') {
            fputc(b[i], f);
        } else {
            fprintf(f, "\\x%02X", b[i]);
        }
    }
    fputs("\"\n", f);
}

static void dict_string(FILE *f, const char *s) {
    dict_entry(f, (const uint8_t *)s, strlen(s));
}

/* An LCM fingerprint as it starts a message: the 64-bit hash, big-endian. */
static void dict_hash(FILE *f, int64_t h) {
    uint8_t b[8];
    const uint64_t u = (uint64_t)h;
    for (int k = 0; k < 8; ++k) b[k] = (uint8_t)(u >> (56 - 8 * k));
    dict_entry(f, b, 8);
}

static FILE *open_dict(const char *dir, const char *name) {
    char path[4096];
    snprintf(path, sizeof path, "%s/dicts/%s", dir, name);
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        fprintf(stderr, "sfd-fuzz-seeds: cannot write %s\n", path);
        g_failed = 1;
    }
    return f;
}

static void close_dict(FILE *f, const char *name) {
    if (f != NULL && fclose(f) != 0) {
        fprintf(stderr, "sfd-fuzz-seeds: cannot write dictionary %s\n", name);
        g_failed = 1;
    }
}

/* The fuzzers' dictionaries (libFuzzer -dict), made from the build's own types and files so they
 * never go stale: OUTDIR/dicts/wire.dict (every sfd type's fingerprint, the values the decoders
 * check: camera models, capacities), log_reader.dict (LCM's log sync word, the channel names, the
 * fingerprints), config.dict (every key of the shipped YAML and the loader's special tokens). */
static void write_dicts(const char *dir, const char *yaml) {
    make_dir(dir, "dicts");
    const int64_t hashes[] = {__sfd_imu_t_get_hash(),           __sfd_camera_info_t_get_hash(),
                              __sfd_feature_frame_t_get_hash(), __sfd_feature_verdict_t_get_hash(),
                              __sfd_nav_state_t_get_hash(),     __sfd_timing_t_get_hash(),
                              __sfd_truth_t_get_hash()};
    static const char *const channels[] = {"IMU",        "CAMERA_INFO", "FEATURES", "SFD_VERDICT",
                                           "SFD_TIMING", "SFD_STATE",   "TRUTH"};
    FILE *w = open_dict(dir, "wire.dict");
    if (w != NULL) {
        for (size_t k = 0; k < sizeof hashes / sizeof hashes[0]; ++k) dict_hash(w, hashes[k]);
        const uint8_t small[] = {0, 1, 2, 3, 0xff};
        for (size_t k = 0; k < sizeof small; ++k) dict_entry(w, &small[k], 1);
        const uint8_t cap512[4] = {0, 0, 2, 0}, cap513[4] = {0, 0, 2, 1},
                      neg1[4] = {0xff, 0xff, 0xff, 0xff};
        dict_entry(w, cap512, 4);
        dict_entry(w, cap513, 4);
        dict_entry(w, neg1, 4);
        const uint8_t nan_be[8] = {0x7f, 0xf8, 0, 0, 0, 0, 0, 0};
        const uint8_t inf_be[8] = {0x7f, 0xf0, 0, 0, 0, 0, 0, 0};
        const uint8_t max_be[8] = {0x7f, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff};
        dict_entry(w, nan_be, 8);
        dict_entry(w, inf_be, 8);
        dict_entry(w, max_be, 8);
    }
    close_dict(w, "wire.dict");
    FILE *l = open_dict(dir, "log_reader.dict");
    if (l != NULL) {
        const uint8_t sync[4] = {0xED, 0xA1, 0xDA, 0x01};
        dict_entry(l, sync, 4);
        for (size_t k = 0; k < sizeof channels / sizeof channels[0]; ++k) {
            dict_string(l, channels[k]);
        }
        for (size_t k = 0; k < sizeof hashes / sizeof hashes[0]; ++k) dict_hash(l, hashes[k]);
        const uint8_t big_len[4] = {0x7f, 0xff, 0xff, 0xff};
        dict_entry(l, big_len, 4);
    }
    close_dict(l, "log_reader.dict");
    FILE *c = open_dict(dir, "config.dict");
    FILE *y = fopen(yaml, "r");
    if (c != NULL) {
        static const char *const tokens[] = {
            "%YAML:1.0", "---",   ": ",  ".nan",  ".inf",       "-.inf", "[ ", " ]", ", ",
            "\"",        "\n   ", "\\n", "1e309", "2147483648", "0x",    "00", "-1", "#"};
        for (size_t k = 0; k < sizeof tokens / sizeof tokens[0]; ++k) dict_string(c, tokens[k]);
        char line[1024];
        int keys = 0;
        while (y != NULL && fgets(line, sizeof line, y) != NULL) {
            const char *p = line;
            while (*p == ' ') ++p;
            size_t n = 0;
            while ((p[n] >= 'a' && p[n] <= 'z') || (p[n] >= '0' && p[n] <= '9') || p[n] == '_') {
                ++n;
            }
            if (n == 0 || p[n] != ':') continue;
            char key[128];
            snprintf(key, sizeof key, "%.*s:", (int)(n < 100 ? n : 100), p);
            dict_string(c, key);
            ++keys;
        }
        if (keys == 0) {
            fprintf(stderr, "sfd-fuzz-seeds: no key read from %s\n", yaml);
            g_failed = 1;
        }
    }
    if (y != NULL) fclose(y);
    close_dict(c, "config.dict");
}

int main(int argc, char **argv) {
    if (argc != 4 || !strcmp(argv[1], "--help")) {
        fprintf(argc == 2 ? stdout : stderr,
                "usage: sfd-fuzz-seeds LOG.lcmlog OUTDIR CONFIG.yaml\n");
        return argc == 2 ? 0 : 2;
    }
    const char *dir = argv[2];
    static sfd_log_reader_t log;
    if (sfd_log_open(&log, argv[1], 0) != SFD_LOG_OK) {
        fprintf(stderr, "sfd-fuzz-seeds: %s\n", log.message);
        sfd_log_close(&log);
        return 2;
    }
    static const char *const subs[3] = {"imu", "camera_info", "features"};
    make_dir(dir, "");
    for (int k = 0; k < 3; ++k) make_dir(dir, subs[k]);
    make_dir(dir, "sequence");
    int per_kind[3] = {0, 0, 0};
    const event_t *first[3] = {NULL, NULL, NULL};
    sfd_log_event_t event;
    sfd_log_status_t st;
    while ((st = sfd_log_next(&log, &event)) == SFD_LOG_OK) {
        const sfd_log_event_t *ev = &event;
        int kind = -1;
        if (!strcmp(ev->channel, "IMU")) kind = FZ_SEQ_IMU;
        if (!strcmp(ev->channel, "CAMERA_INFO")) kind = FZ_SEQ_CAMERA_INFO;
        if (!strcmp(ev->channel, "FEATURES")) kind = FZ_SEQ_FEATURES;
        if (kind >= 0 && g_num_events < MAX_EVENTS) {
            event_t *e = &g_events[g_num_events++];
            e->kind = kind;
            e->size = ev->datalen;
            e->data = malloc((size_t)ev->datalen);
            if (e->data == NULL) return 1;
            memcpy(e->data, ev->data, (size_t)ev->datalen);
            char name[64];
            snprintf(name, sizeof name, "sim_%03d", per_kind[kind]++);
            write_file(dir, subs[kind], name, e->data, (size_t)e->size);
            if (first[kind] == NULL) first[kind] = e;
        }
    }
    sfd_log_close(&log);
    if (st != SFD_LOG_END) {
        fprintf(stderr, "sfd-fuzz-seeds: %s\n", log.message);
        return 2;
    }
    if (per_kind[FZ_SEQ_IMU] == 0 || per_kind[FZ_SEQ_CAMERA_INFO] == 0 ||
        per_kind[FZ_SEQ_FEATURES] == 0) {
        fprintf(stderr, "sfd-fuzz-seeds: %s lacks IMU, CAMERA_INFO or FEATURES events\n", argv[1]);
        return 2;
    }
    edges(dir, "imu", first[FZ_SEQ_IMU], first[FZ_SEQ_CAMERA_INFO]);
    edges(dir, "camera_info", first[FZ_SEQ_CAMERA_INFO], first[FZ_SEQ_IMU]);
    edges(dir, "features", first[FZ_SEQ_FEATURES], first[FZ_SEQ_IMU]);

    /* sequences: the whole log under a few configurations, compact and wire FEATURES, prefixes */
    static const uint8_t configs[] = {0x00, 0x01, 0x04, 0x08, 0x13, 0x62};
    for (size_t c = 0; c < sizeof configs; ++c) {
        char name[64];
        snprintf(name, sizeof name, "sim_compact_cfg%02x", configs[c]);
        write_file(dir, "sequence", name, g_seq, sequence_of(configs[c], 1, g_num_events, 0));
    }
    write_file(dir, "sequence", "sim_wire", g_seq, sequence_of(0x00, 0, g_num_events, 0));
    write_file(dir, "sequence", "sim_compact_after_imu_burst", g_seq,
               sequence_of(0x00, 1, g_num_events, SFD_IMU_RING_CAPACITY + 52));
    for (int n = 1; n < g_num_events; n *= 3) {
        char name[64];
        snprintf(name, sizeof name, "sim_compact_first_%03d", n);
        write_file(dir, "sequence", name, g_seq, sequence_of(0x00, 1, n, 0));
    }
    const uint8_t empty = 0;
    write_file(dir, "sequence", "edge_empty", &empty, 0);
    write_file(dir, "sequence", "edge_config_only", &empty, 1);
    size_t len = sequence_of(0x00, 1, g_num_events, 0);
    write_file(dir, "sequence", "edge_truncated_record", g_seq, len > 5 ? len - 5 : len);
    len = 1;
    len = append(len, FZ_SEQ_CAMERA_INFO, first[FZ_SEQ_IMU]->data, (size_t)first[FZ_SEQ_IMU]->size);
    len = append(len, FZ_SEQ_IMU, first[FZ_SEQ_CAMERA_INFO]->data,
                 (size_t)first[FZ_SEQ_CAMERA_INFO]->size / 2);
    write_file(dir, "sequence", "edge_wrong_channels", g_seq, len);

    write_dicts(dir, argv[3]);
    for (int i = 0; i < g_num_events; ++i) free(g_events[i].data);
    printf("sfd-fuzz-seeds: %d IMU, %d CAMERA_INFO, %d FEATURES events from %s into %s\n",
           per_kind[0], per_kind[1], per_kind[2], argv[1], dir);
    return g_failed ? 1 : 0;
}
