/* SPDX-License-Identifier: MIT */
/* Output files of the sfd tools: no output may be an input, and no failed run leaves a
 * half-written output (docs/deploy.md, "Reading logs and writing outputs").
 *
 * sfd_same_file(): two paths name one file when both exist and have the same device and inode
 * (a hard link, a symbolic link, ./X and X), or when one does not exist yet and both resolve to
 * the same directory entry.
 *
 * sfd_out_begin() reserves where an output is written: a new temporary file next to it
 * (".NAME.XXXXXX" in the same directory, mode 0666 less the umask) that sfd_out_commit() renames
 * over the output, so the output appears whole or not at all; sfd_out_discard() removes it. An
 * output that already exists and is not a regular file (/dev/null, /dev/full, a FIFO) cannot be
 * replaced by a rename: it is written directly (write_path is the output itself), and the caller
 * must check every write and the final fflush/fclose, as it must anyway. An output that is a
 * symbolic link to a file is written through the link (the file it names is replaced). */
#ifndef SFD_OUTPUT_H
#define SFD_OUTPUT_H

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* 1 when `a` and `b` name the same file, else 0. */
int sfd_same_file(const char *a, const char *b);

typedef struct {
    char path[4096];       /* the output as given */
    char target[4096];     /* the file replaced on commit (`path`, or what its symlink names) */
    char write_path[4096]; /* where the caller writes: the temporary file, or `path` (direct) */
    int direct;            /* 1: a special file, written in place */
    int active;            /* 1 between begin and commit/discard */
} sfd_out_t;

/* 0, or -1 with a one-line reason naming the path in err. */
int sfd_out_begin(sfd_out_t *o, const char *path, char *err, size_t err_len);
/* Renames the temporary file over the output (nothing for a direct output): 0, or -1 with err. */
int sfd_out_commit(sfd_out_t *o, char *err, size_t err_len);
/* Removes the temporary file (nothing for a direct output). */
void sfd_out_discard(sfd_out_t *o);

/* Closes `f` after checking it: 0 when every write, the fflush and the fclose succeeded. */
int sfd_close_checked(FILE *f);

#ifdef __cplusplus
}
#endif

#endif /* SFD_OUTPUT_H */
