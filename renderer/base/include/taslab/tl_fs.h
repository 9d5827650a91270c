/* tl_fs.h — files and folders: mkdir -p, the one atomic-write helper, and small path checks.
 *
 * Atomic writes (every file taslab writes goes through tl_atomic): the content is written to a hidden
 * temporary file in the destination folder, named ".NAME.tmp.XXXXXX" (unique per process and call,
 * mkstemp), every write is checked, the file is flushed and fsync'ed, closed, renamed over NAME, and
 * the folder is fsync'ed. A crash or a full disk therefore never leaves a truncated file under the
 * final name, and a reader sees either the old or the new file. tl_fs_clean_temps removes temporary
 * files that a killed process left behind.
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
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TL_PATH_MAX 4096

/* Creates a folder and its parents (mkdir -p). TL_ERR_OUTPUT when a part exists as a file or cannot be
 * created. */
int tl_mkdirs(const char *path, char *err, size_t err_size);

typedef struct tl_atomic {
	char path[TL_PATH_MAX]; /* final name */
	char tmp[TL_PATH_MAX];  /* temporary name in the same folder */
	FILE *f;                /* open stream on tmp (NULL after tl_atomic_detach) */
	bool open;              /* tmp exists and is ours */
} tl_atomic;

/* Creates the temporary file for `path` (its folder must exist). TL_ERR_OUTPUT on failure. */
int tl_atomic_open(tl_atomic *a, const char *path, char *err, size_t err_size);
/* Closes the stream but keeps the temporary file, for writers that write by file name (to a->tmp). */
int tl_atomic_detach(tl_atomic *a, char *err, size_t err_size);
/* Flushes, checks every write, fsyncs, closes, renames into place and fsyncs the folder. On any failure
 * the temporary file is removed and TL_ERR_OUTPUT returned (ENOSPC and EIO are reported here). */
int tl_atomic_commit(tl_atomic *a, char *err, size_t err_size);
/* Discards the temporary file (safe to call after a commit or on a zeroed struct). */
void tl_atomic_abort(tl_atomic *a);

/* Writes `size` bytes to `path` atomically. */
int tl_write_file(const char *path, const void *data, size_t size, char *err, size_t err_size);
/* Reads a whole file (NUL-terminated; *data malloc'ed, caller frees). TL_ERR_INPUT when missing or larger
 * than `max_size` bytes. */
int tl_read_file(const char *path, size_t max_size, char **data, size_t *size, char *err, size_t err_size);

/* Removes the temporary files ".*.tmp.XXXXXX" of tl_atomic (left by a killed process) in `dir`;
 * returns how many were removed. Only names of exactly that shape are touched. */
int tl_fs_clean_temps(const char *dir);

bool tl_is_dir(const char *path);
bool tl_is_file(const char *path);
/* True when a and b name the same existing file or folder (same device and inode), or when `inner`
 * lies inside folder `outer` (after resolving both with realpath; `inner` may not exist yet: its
 * existing parent is resolved). Used so that no command writes over its own inputs. */
bool tl_same_file(const char *a, const char *b);
bool tl_path_inside(const char *inner, const char *outer);

#ifdef __cplusplus
}
#endif
#endif
