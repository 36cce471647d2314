// SPDX-License-Identifier: MIT
// fuzz.config: the input is a whole configuration file, read by sfd-node's and sfd-replay's
// loader (apps/common/sfd_app_config: cv::FileStorage, then the checks of syntax, key names and
// types) and validated. Oracles, beyond no crash and no sanitizer report: a refusal is one line
// naming the file; a configuration validate() accepts starts a node (sfd_node_init() == SFD_OK,
// the promise of sfd_app_config.hpp), and so do the defaults the loader starts from.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_harness.h"
#include "sfd_app_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

namespace {

void check(bool cond, const char *what) {
    if (!cond) fz_fail(__FILE__, __LINE__, what);
}

void ignore_publish(void *, sfd_node_output_t, const void *, int32_t, int64_t) {}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const int fd = memfd_create("fuzz_config", 0);
    check(fd >= 0, "memfd_create");
    size_t done = 0;
    while (done < size) {
        const ssize_t w = write(fd, data + done, size - done);
        check(w > 0, "write");
        done += static_cast<size_t>(w);
    }
    const std::string path = "/proc/self/fd/" + std::to_string(fd);
    sfdapp::AppConfig cfg;
    std::string err;
    const bool read = sfdapp::read_config(path, &cfg, &err);
    if (!read) {
        check(!err.empty() && err.find('\n') == std::string::npos, "a one-line reason");
        check(err.compare(0, path.size(), path) == 0, "the reason names the file");
    } else if (sfdapp::validate(cfg, &err)) {
        check(sfd_node_init(&g_fz_node, &cfg.node, ignore_publish, nullptr, nullptr) == SFD_OK,
              "a validated configuration starts a node");
    } else {
        check(!err.empty() && err.find('\n') == std::string::npos, "a one-line reason");
    }
    close(fd);
    return 0;
}
