/* SPDX-License-Identifier: MIT */
/* Output files: input/output identity and temporary-file-and-rename (sfd_output.h). */
#include "sfd_output.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The directory part of `path` ("." when it has none) in dir, and the last component in base. */
static void split_path(const char *path, char *dir, size_t dir_len, const char **base) {
    const char *slash = strrchr(path, '/');
    if (slash == NULL) {
        snprintf(dir, dir_len, ".");
        *base = path;
    } else if (slash == path) {
        snprintf(dir, dir_len, "/");
        *base = slash + 1;
    } else {
        snprintf(dir, dir_len, "%.*s", (int)(slash - path), path);
        *base = slash + 1;
    }
}

/* The canonical name of a path whose last component may not exist yet: realpath of its directory
 * plus the last component. 0, or -1 when the directory does not resolve. */
static int canonical(const char *path, char *out, size_t out_len) {
    char resolved[PATH_MAX];
    if (realpath(path, resolved) != NULL) {
        snprintf(out, out_len, "%s", resolved);
        return 0;
    }
    char dir[PATH_MAX];
    const char *base = NULL;
    split_path(path, dir, sizeof dir, &base);
    if (realpath(dir, resolved) == NULL) return -1;
    snprintf(out, out_len, "%s/%s", strcmp(resolved, "/") ? resolved : "", base);
    return 0;
}

int sfd_same_file(const char *a, const char *b) {
    if (strcmp(a, b) == 0) return 1;
    struct stat sa, sb;
    const int ea = stat(a, &sa) == 0, eb = stat(b, &sb) == 0;
    if (ea && eb) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    char ca[PATH_MAX + 256], cb[PATH_MAX + 256];
    if (canonical(a, ca, sizeof ca) != 0 || canonical(b, cb, sizeof cb) != 0) return 0;
    return strcmp(ca, cb) == 0;
}

int sfd_out_begin(sfd_out_t *o, const char *path, char *err, size_t err_len) {
    memset(o, 0, sizeof *o);
    snprintf(o->path, sizeof o->path, "%s", path);
    snprintf(o->target, sizeof o->target, "%s", path);
    struct stat st;
    if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode)) {
        char resolved[PATH_MAX];
        if (realpath(path, resolved) != NULL) snprintf(o->target, sizeof o->target, "%s", resolved);
    }
    if (stat(o->target, &st) == 0) {
        if (S_ISDIR(st.st_mode)) {
            snprintf(err, err_len, "%s: is a directory", path);
            return -1;
        }
        if (!S_ISREG(st.st_mode)) { /* /dev/null, /dev/full, a FIFO: written in place */
            snprintf(o->write_path, sizeof o->write_path, "%s", path);
            o->direct = 1;
            o->active = 1;
            return 0;
        }
    }
    char dir[PATH_MAX];
    const char *base = NULL;
    split_path(o->target, dir, sizeof dir, &base);
    if (*base == '\0') {
        snprintf(err, err_len, "%s: not a file name", path);
        return -1;
    }
    if (snprintf(o->write_path, sizeof o->write_path, "%s/.%s.XXXXXX", dir, base) >=
        (int)sizeof o->write_path) {
        snprintf(err, err_len, "%s: path too long", path);
        return -1;
    }
    const int fd = mkstemp(o->write_path);
    if (fd < 0) {
        snprintf(err, err_len, "%s: cannot create a file in %s (%s)", path, dir, strerror(errno));
        return -1;
    }
    const mode_t mask = umask(0);
    umask(mask);
    const int chmod_failed = fchmod(fd, 0666 & ~mask) != 0;
    close(fd);
    if (chmod_failed) {
        snprintf(err, err_len, "%s: cannot set the mode of %s (%s)", path, o->write_path,
                 strerror(errno));
        unlink(o->write_path);
        return -1;
    }
    o->active = 1;
    return 0;
}

int sfd_out_commit(sfd_out_t *o, char *err, size_t err_len) {
    if (!o->active) {
        snprintf(err, err_len, "%s: not open", o->path);
        return -1;
    }
    o->active = 0;
    if (o->direct) return 0;
    if (rename(o->write_path, o->target) != 0) {
        snprintf(err, err_len, "%s: cannot rename %s into place (%s)", o->path, o->write_path,
                 strerror(errno));
        unlink(o->write_path);
        return -1;
    }
    return 0;
}

void sfd_out_discard(sfd_out_t *o) {
    if (o->active && !o->direct) unlink(o->write_path);
    o->active = 0;
}

int sfd_close_checked(FILE *f) {
    const int bad = fflush(f) != 0 || ferror(f) != 0;
    return (fclose(f) != 0 || bad) ? -1 : 0;
}
