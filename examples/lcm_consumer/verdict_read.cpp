// SPDX-License-Identifier: MIT
// The installed C++ types (header-only <sfd/feature_verdict_t.hpp>): decodes the message that
// verdict_roundtrip wrote and checks its fields. Exit 0 when they are the expected ones.
#include <cstdio>
#include <fstream>
#include <iterator>
#include <vector>

#include <sfd/feature_verdict_t.hpp>

int main(int argc, char **argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: verdict_read IN.bin\n");
        return 2;
    }
    std::ifstream in(argv[1], std::ios::binary);
    const std::vector<char> buf((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
    static sfd::feature_verdict_t m;
    const int n = m.decode(buf.data(), 0, static_cast<int>(buf.size()));
    const bool ok = n == static_cast<int>(buf.size()) && m.utime == 1234567 && m.camera_id == 1 &&
                    m.num_features == 3 && m.track_id[1] == 12 &&
                    m.status[1] == sfd::feature_verdict_t::SPURIOUS && m.statistic[1] == 3.25 &&
                    m.stage[0] == sfd::feature_verdict_t::PARITY && m.stage[2] == 0;
    std::printf("C++ sfd::feature_verdict_t: decoded %d bytes: %s\n", n, ok ? "ok" : "WRONG");
    return ok ? 0 : 1;
}
