// SPDX-License-Identifier: MIT
#include "core_private.hpp"
#include "sfd/sfd_version.h"

extern "C" uint32_t sfd_version(void) {
    return static_cast<uint32_t>(SFD_VERSION);
}

extern "C" const char *sfd_status_str(sfd_status_t status) {
    switch (status) {
        case SFD_OK:
            return "SFD_OK";
        case SFD_ERR_INVAL:
            return "SFD_ERR_INVAL";
        case SFD_ERR_CAPACITY:
            return "SFD_ERR_CAPACITY";
        case SFD_ERR_ORDER:
            return "SFD_ERR_ORDER";
        case SFD_ERR_NUMERIC:
            return "SFD_ERR_NUMERIC";
        case SFD_ERR_STATE:
            return "SFD_ERR_STATE";
        case SFD_ERR_RANGE:
            return "SFD_ERR_RANGE";
        case SFD_ERR_DOMAIN:
            return "SFD_ERR_DOMAIN";
    }
    return "SFD_ERR_UNKNOWN";
}
