/* tl_fs.h — files and folders: mkdir -p, the one atomic-write helper, and small path checks.
 *
 * Atomic writes (every file taslab writes goes through tl_atomic): the content is written to a hidden
 * temporary file in the destination folder, named ".NAME.tmp.XXXXXX" (unique per process and call,
 * mkstemp), every write is checked, the file is flushed and fsync'ed, closed, renamed over NAME, and
 * the folder is fsync'ed. A crash or a full disk therefore never leaves a truncated file under the
 * final name, and a reader sees either the old or the new file. While a temporary file is ours we hold
 * an flock on it (the kernel drops it when the process dies), so tl_fs_clean_temps can tell the
 * temporary files that a killed process left behind from those a running writer still owns; every
 * command calls it on its output folders.
 *
 *   tl_atomic a;
 *   if (tl_atomic_open(&a, path, err, n)) return ...;      // a.f: a stdio stream on the temporary file
 *   fprintf(a.f, ...);
 *   return tl_atomic_commit(&a, err, n);                    // or tl_atomic_abort(&a) on failure
 *
 * Writers that need a file name instead of a stream (OpenImageIO, libavformat, SQLite) call
 * tl_atomic_detach after tl_atomic_open, write to a.tmp, and then commit as above.
 */
#ifndef TASLAB_TL_FS_H
#define TASLAB_TL_FS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TL_PATH_MAX 4096

/* Creates a folder and its parents (mkdir -p) for outputs, and removes the temporary files that killed
 * writers left in it (tl_fs_clean_temps). TL_ERR_ARG when a part exists and is not a folder (a file,
 * /dev/null), TL_ERR_OUTPUT when one cannot be created. */
int tl_mkdirs(const char *path, char *err, size_t err_size);

typedef struct tl_atomic {
	char path[TL_PATH_MAX]; /* final name */
	char tmp[TL_PATH_MAX];  /* temporary name in the same folder */
	FILE *f;                /* open stream on tmp (NULL after tl_atomic_detach) */
	bool open;              /* tmp exists and is ours */
	int lock_fd;            /* holds the flock on tmp while open (valid only when open) */
} tl_atomic;

/* Creates the temporary file for `path` (its folder must exist). TL_ERR_OUTPUT on failure. */
int tl_atomic_open(tl_atomic *a, const char *path, char *err, size_t err_size);
/* Closes the stream but keeps the temporary file, for writers that write by file name (to a->tmp). */
int tl_atomic_detach(tl_atomic *a, char *err, size_t err_size);
/* Flushes, checks every write, fsyncs, closes, renames into place and fsyncs the folder. On any failure
 * the temporary file is removed and TL_ERR_OUTPUT returned (ENOSPC and EIO are reported here). */
int tl_atomic_commit(tl_atomic *a, char *err, size_t err_size);
/* Gives up the lock of a detached temporary file, for sets of thousands of files (each lock holds a file
 * descriptor). A cleaner may then take the file for abandoned; the commit then fails with a message. */
void tl_atomic_unlock(tl_atomic *a);
/* Discards the temporary file (safe to call after a commit or on a zeroed struct). */
void tl_atomic_abort(tl_atomic *a);

/* A set of outputs that belong together (a tally's tables, a tone-mapped sequence): every temporary file
 * is flushed, checked and fsync'ed first, and only when all of them are good are they renamed into place.
 * On a failure every temporary file of the set is removed and no final name has changed (a rename failing
 * halfway, which needs a vanished folder, is reported). Zeroed entries are skipped. */
int tl_atomic_commit_set(tl_atomic *a, size_t n, char *err, size_t err_size);
void tl_atomic_abort_set(tl_atomic *a, size_t n);

/* Writes `size` bytes to `path` atomically. */
int tl_write_file(const char *path, const void *data, size_t size, char *err, size_t err_size);
/* Opens `path` for reading only when it is a regular file of at most `max_size` bytes (issue 31.6: a device such
 * as /dev/zero, a FIFO or a folder is refused at once, never read or waited on): *fd (the caller closes it) and
 * *size from fstat. TL_ERR_INPUT with one line saying what the path is otherwise. */
int tl_open_regular(const char *path, uint64_t max_size, int *fd, uint64_t *size, char *err, size_t err_size);
/* Reads a whole regular file (tl_open_regular; NUL-terminated; *data malloc'ed, caller frees). TL_ERR_INPUT when
 * missing, not a regular file or larger than `max_size` bytes. */
int tl_read_file(const char *path, size_t max_size, char **data, size_t *size, char *err, size_t err_size);

/* Removes the temporary files ".*.tmp.XXXXXX" of tl_atomic that a killed process left in `dir`;
 * returns how many were removed. Only names of exactly that shape are touched, and only when no process
 * holds their lock (a writer that is still running keeps its file); SQLite's -wal, -shm and -journal files
 * beside a removed one go with it. */
int tl_fs_clean_temps(const char *dir);
/* tl_fs_clean_temps on the folder of the file `path`. */
int tl_fs_clean_temps_beside(const char *path);

/* Checks, before any long work, that folder `dir` can take outputs: creates it (and its parents) and
 * creates and removes a temporary file in it, so a read-only file system, missing permissions or an
 * unusable path fail now. TL_ERR_OUTPUT with one line naming `what` (e.g. "--out"). */
int tl_check_out_dir(const char *dir, const char *what, char *err, size_t err_size);

bool tl_is_dir(const char *path);
bool tl_is_file(const char *path);
/* True when a and b name the same existing file or folder (same device and inode), or when `inner`
 * lies inside folder `outer` (after resolving both with realpath; `inner` may not exist yet: its
 * existing parent is resolved). Used so that no command writes over its own inputs. */
bool tl_same_file(const char *a, const char *b);
bool tl_path_inside(const char *inner, const char *outer);
/* True when a and b are the same file: the same existing file (tl_same_file: symlinks, hard links,
 * other spellings) or, when they do not exist yet, the same path after resolving their parents. */
bool tl_same_path(const char *a, const char *b);

#ifdef __cplusplus
}
#endif
#endif
