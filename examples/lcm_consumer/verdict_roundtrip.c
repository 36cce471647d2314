/* SPDX-License-Identifier: MIT */
/* The installed C types (libsfd_lcmtypes, <sfd_feature_verdict_t.h>): encodes a three-feature
 * verdict into a caller-owned buffer, decodes it back (no heap: fixed-size arrays only), checks
 * every field, and writes the encoded message (fingerprint first) to the file given, for the
 * C++, Python and Java readers. Exit 0 when the round trip is exact. */
#include <stdio.h>
#include <string.h>

#include <sfd_feature_verdict_t.h>

static sfd_feature_verdict_t g_out, g_in; /* 512-entry arrays: static */
static unsigned char g_buf[8 + 16 + 512 * (8 + 1 + 8 + 1)];

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: verdict_roundtrip OUT.bin\n");
        return 2;
    }
    g_out.utime = 1234567;
    g_out.camera_id = 1;
    g_out.num_features = 3;
    const int64_t ids[3] = {11, 12, 13};
    const int8_t status[3] = {SFD_FEATURE_VERDICT_T_CONSISTENT, SFD_FEATURE_VERDICT_T_SPURIOUS,
                              SFD_FEATURE_VERDICT_T_UNTESTED};
    const double stat[3] = {0.5, 3.25, 0.0};
    for (int i = 0; i < 3; ++i) {
        g_out.track_id[i] = ids[i];
        g_out.status[i] = status[i];
        g_out.statistic[i] = stat[i];
        g_out.stage[i] = (int8_t)(i < 2 ? SFD_FEATURE_VERDICT_T_PARITY : 0);
    }
    const int size = sfd_feature_verdict_t_encoded_size(&g_out);
    if (size != (int)sizeof g_buf) {
        fprintf(stderr, "encoded size %d, expected %d\n", size, (int)sizeof g_buf);
        return 1;
    }
    if (sfd_feature_verdict_t_encode(g_buf, 0, (int)sizeof g_buf, &g_out) != size) return 1;
    if (sfd_feature_verdict_t_decode(g_buf, 0, size - 1, &g_in) >= 0) return 1; /* short: refused */
    if (sfd_feature_verdict_t_decode(g_buf, 0, size, &g_in) != size) return 1;
    if (memcmp(&g_out, &g_in, sizeof g_out) != 0) {
        fprintf(stderr, "decoded message differs from the encoded one\n");
        return 1;
    }
    FILE *f = fopen(argv[1], "wb");
    if (f == NULL || fwrite(g_buf, 1, (size_t)size, f) != (size_t)size || fclose(f) != 0) {
        fprintf(stderr, "%s: cannot write\n", argv[1]);
        return 2;
    }
    printf("sfd_feature_verdict_t: %d bytes encoded and decoded exactly, hash %016llx\n", size,
           (unsigned long long)__sfd_feature_verdict_t_get_hash());
    return 0;
}
