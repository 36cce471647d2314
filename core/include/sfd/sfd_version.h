/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_version.h
 * @brief The core's version: the headers' (SFD_VERSION, at compile time) and the library's
 *        (sfd_version(), at run time). A consumer can compare the two to find a library that
 *        is not the one its headers came with.
 */
#ifndef SFD_VERSION_H
#define SFD_VERSION_H

#include <stdint.h>

#define SFD_VERSION_MAJOR 0
#define SFD_VERSION_MINOR 2
#define SFD_VERSION ((SFD_VERSION_MAJOR << 16) | SFD_VERSION_MINOR)

#ifdef __cplusplus
extern "C" {
#endif

/** @brief The library's version, (major << 16) | minor, as SFD_VERSION was when it was built. */
uint32_t sfd_version(void);

#ifdef __cplusplus
}
#endif

#endif /* SFD_VERSION_H */
