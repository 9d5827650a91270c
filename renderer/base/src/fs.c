/* fs.c — mkdir -p, atomic writes, temp-file cleanup, path checks (tl_fs.h). */
#define _GNU_SOURCE /* realpath, mkostemp */
#include "taslab/tl_fs.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/tl_error.h"

int tl_mkdirs(const char *path, char *err, size_t err_size)
{
	char buf[TL_PATH_MAX];
	if (!path || !*path)
		return tl_error(err, err_size, TL_ERR_ARG, "empty folder name");
	if (snprintf(buf, sizeof buf, "%s", path) >= (int)sizeof buf)
		return tl_error(err, err_size, TL_ERR_ARG, "%s: path too long", path);
	for (char *p = buf + 1;; p++) {
		if (*p == '/' || *p == 0) {
			char c = *p;
			*p = 0;
			if (mkdir(buf, 0777) != 0 && errno != EEXIST)
				return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot create folder: %s (choose a writable --out)",
						buf, strerror(errno));
			struct stat sb;
			/* a file, /dev/null, a FIFO where a folder is asked for: the caller's choice, so bad input (exit 2,
			 * issue 31.9) */
			if (stat(buf, &sb) != 0 || !S_ISDIR(sb.st_mode))
				return tl_error(err, err_size, TL_ERR_ARG, "%s: exists and is not a folder (choose another --out)",
						buf);
			*p = c;
			if (!c)
				break;
		}
	}
	tl_fs_clean_temps(path); /* an output folder: what killed writers left in it goes */
	return TL_OK;
}

/* The folder part of `path` ("." when there is none) into dir. */
static void dir_of(const char *path, char *dir, size_t n)
{
	const char *slash = strrchr(path, '/');
	if (!slash)
		snprintf(dir, n, ".");
	else if (slash == path)
		snprintf(dir, n, "/");
	else
		snprintf(dir, n, "%.*s", (int)(slash - path), path);
}

/* Drops the lock of an open temporary file (its flock goes with the descriptor). */
static void release(tl_atomic *a)
{
	if (a->open && a->lock_fd >= 0)
		close(a->lock_fd);
	a->lock_fd = -1;
}

int tl_atomic_open(tl_atomic *a, const char *path, char *err, size_t err_size)
{
	memset(a, 0, sizeof *a);
	a->lock_fd = -1;
	if (!path || !*path)
		return tl_error(err, err_size, TL_ERR_ARG, "empty output file name");
	const char *slash = strrchr(path, '/');
	const char *base = slash ? slash + 1 : path;
	if (!*base)
		return tl_error(err, err_size, TL_ERR_ARG, "%s: names a folder, not a file", path);
	if (snprintf(a->path, sizeof a->path, "%s", path) >= (int)sizeof a->path ||
	    snprintf(a->tmp, sizeof a->tmp, "%.*s.%s.tmp.XXXXXX", (int)(base - path), path, base) >= (int)sizeof a->tmp)
		return tl_error(err, err_size, TL_ERR_ARG, "%s: path too long", path);
	char pattern[TL_PATH_MAX];
	snprintf(pattern, sizeof pattern, "%s", a->tmp);
	int fd = -1;
	/* The lock lives on its own descriptor, so it outlasts tl_atomic_detach (which closes the stream). A cleaner
	 * (tl_fs_clean_temps) may have taken the new file for an abandoned one before we locked it: then the name is
	 * gone or another file's, and we take a new name. */
	for (int attempt = 0; attempt < 100 && fd < 0; attempt++) {
		snprintf(a->tmp, sizeof a->tmp, "%s", pattern);
		if ((fd = mkostemp(a->tmp, O_CLOEXEC)) < 0) {
			int e = errno;
			char dir[TL_PATH_MAX];
			dir_of(path, dir, sizeof dir);
			if (e == ENOENT)
				return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: the folder %s does not exist (create it "
						"first)", path, dir);
			return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: %s", path, strerror(e));
		}
		struct stat mine, named;
		if ((a->lock_fd = fcntl(fd, F_DUPFD_CLOEXEC, 0)) < 0 || fstat(fd, &mine) != 0) {
			int e = errno;
			if (a->lock_fd >= 0)
				close(a->lock_fd);
			close(fd);
			unlink(a->tmp);
			return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: %s", path, strerror(e));
		}
		/* A file system without flock (some cluster ones): no lock, and no cleaner can take the file either. */
		if (flock(a->lock_fd, LOCK_EX) != 0)
			break;
		if (stat(a->tmp, &named) != 0 || named.st_ino != mine.st_ino || named.st_dev != mine.st_dev) {
			close(a->lock_fd);
			close(fd);
			fd = -1;
		}
	}
	if (fd < 0)
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: temporary files keep vanishing", path);
	fchmod(fd, 0644);
	a->open = true;
	a->f = fdopen(fd, "wb");
	if (!a->f) {
		int e = errno;
		close(fd);
		tl_atomic_abort(a);
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: %s", path, strerror(e));
	}
	return TL_OK;
}

int tl_atomic_detach(tl_atomic *a, char *err, size_t err_size)
{
	if (a->f) {
		int bad = fclose(a->f) != 0;
		int e = errno;
		a->f = NULL;
		if (bad) {
			tl_atomic_abort(a);
			return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: %s", a->path, strerror(e));
		}
	}
	return TL_OK;
}

static void fsync_dir(const char *path)
{
	char dir[TL_PATH_MAX];
	dir_of(path, dir, sizeof dir);
	int fd = open(dir, O_RDONLY | O_DIRECTORY);
	if (fd >= 0) {
		fsync(fd); /* best effort: some file systems refuse fsync on folders */
		close(fd);
	}
}

/* Everything of a commit but the rename: flush, check every write, fsync, close. 0 or an errno. */
static int prepare(tl_atomic *a)
{
	int e = 0;
	if (a->f) {
		if (fflush(a->f) != 0 || ferror(a->f))
			e = errno ? errno : EIO;
		if (!e && fsync(fileno(a->f)) != 0)
			e = errno;
		if (fclose(a->f) != 0 && !e)
			e = errno ? errno : EIO;
		a->f = NULL;
	} else {
		int fd = open(a->tmp, O_RDONLY | O_CLOEXEC);
		if (fd < 0 || fsync(fd) != 0)
			e = errno;
		if (fd >= 0)
			close(fd);
	}
	return e;
}

int tl_atomic_commit(tl_atomic *a, char *err, size_t err_size)
{
	if (!a->open)
		return tl_error(err, err_size, TL_ERR_INTERNAL, "%s: commit without an open temporary file", a->path);
	int e = prepare(a);
	if (!e && rename(a->tmp, a->path) != 0)
		e = errno;
	if (e) {
		tl_atomic_abort(a);
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: %s", a->path, strerror(e));
	}
	release(a);
	a->open = false;
	fsync_dir(a->path);
	return TL_OK;
}

void tl_atomic_unlock(tl_atomic *a)
{
	release(a);
}

void tl_atomic_abort(tl_atomic *a)
{
	if (a->f) {
		fclose(a->f);
		a->f = NULL;
	}
	if (a->open) {
		unlink(a->tmp);
		release(a);
		a->open = false;
	}
}

int tl_atomic_commit_set(tl_atomic *a, size_t n, char *err, size_t err_size)
{
	for (size_t i = 0; i < n; i++) {
		int e = a[i].open ? prepare(&a[i]) : 0;
		if (e) {
			tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: %s", a[i].path, strerror(e));
			tl_atomic_abort_set(a, n);
			return TL_ERR_OUTPUT;
		}
	}
	for (size_t i = 0; i < n; i++) {
		if (!a[i].open)
			continue;
		if (rename(a[i].tmp, a[i].path) != 0) {
			tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: %s (the files before it were written)", a[i].path,
				 strerror(errno));
			tl_atomic_abort_set(a, n);
			return TL_ERR_OUTPUT;
		}
		release(&a[i]);
		a[i].open = false;
		fsync_dir(a[i].path);
	}
	return TL_OK;
}

void tl_atomic_abort_set(tl_atomic *a, size_t n)
{
	for (size_t i = 0; i < n; i++)
		tl_atomic_abort(&a[i]);
}

int tl_write_file(const char *path, const void *data, size_t size, char *err, size_t err_size)
{
	tl_atomic a;
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	if (size && fwrite(data, 1, size, a.f) != size) {
		int e = errno;
		tl_atomic_abort(&a);
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: %s", path, strerror(e));
	}
	return tl_atomic_commit(&a, err, err_size);
}

int tl_open_regular(const char *path, uint64_t max_size, int *fd, uint64_t *size, char *err, size_t err_size)
{
	*fd = -1;
	*size = 0;
	/* O_NONBLOCK: opening a FIFO must not wait for a writer (it is refused just below) */
	int f = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	if (f < 0)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: cannot read: %s", path, strerror(errno));
	struct stat sb;
	if (fstat(f, &sb)) {
		int e = errno;
		close(f);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: cannot read: %s", path, strerror(e));
	}
	if (!S_ISREG(sb.st_mode)) {
		close(f);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: not a regular file (%s); give a file", path,
				S_ISDIR(sb.st_mode) ? "a folder" : S_ISFIFO(sb.st_mode) ? "a pipe" : S_ISSOCK(sb.st_mode) ? "a socket" : "a device");
	}
	if ((uint64_t)sb.st_size > max_size) {
		close(f);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: larger than %llu bytes", path, (unsigned long long)max_size);
	}
	int fl = fcntl(f, F_GETFL);
	if (fl >= 0)
		fcntl(f, F_SETFL, fl & ~O_NONBLOCK);
	*fd = f;
	*size = (uint64_t)sb.st_size;
	return TL_OK;
}

int tl_read_file(const char *path, size_t max_size, char **data, size_t *size, char *err, size_t err_size)
{
	*data = NULL;
	if (size)
		*size = 0;
	int fd;
	uint64_t len;
	int rc = tl_open_regular(path, max_size, &fd, &len, err, err_size);
	if (rc)
		return rc;
	/* exactly the size fstat gave, and not a byte more (a file growing while read is an error, not a longer read) */
	char *buf = malloc((size_t)len + 1);
	if (!buf) {
		close(fd);
		return tl_error(err, err_size, TL_ERR_NOMEM, "%s: out of memory", path);
	}
	size_t got = 0;
	while (got < len) {
		ssize_t n = read(fd, buf + got, (size_t)len - got);
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0) {
			rc = n < 0 ? tl_error(err, err_size, TL_ERR_INPUT, "%s: read error: %s", path, strerror(errno))
				   : tl_error(err, err_size, TL_ERR_INPUT, "%s: changed while being read (shorter); try again", path);
			break;
		}
		got += (size_t)n;
	}
	char extra;
	if (!rc && read(fd, &extra, 1) > 0)
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: changed while being read (longer); try again", path);
	close(fd);
	if (rc) {
		free(buf);
		return rc;
	}
	buf[len] = 0;
	*data = buf;
	if (size)
		*size = (size_t)len;
	return TL_OK;
}

/* ".NAME.tmp.XXXXXX" with six characters of mkstemp's alphabet at the end. */
static bool is_temp_name(const char *n)
{
	size_t len = strlen(n);
	if (n[0] != '.' || len < 1 + 1 + 5 + 6)
		return false;
	if (strncmp(n + len - 11, ".tmp.", 5) != 0)
		return false;
	for (size_t i = len - 6; i < len; i++) {
		char c = n[i];
		if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')))
			return false;
	}
	return true;
}

/* Removes temporary file `p` when nobody holds its lock (its writer died), unlinking it while we hold the lock
 * and only if the name still refers to the file we locked (a writer may have renamed it into place meanwhile). */
static bool remove_abandoned(const char *p)
{
	int fd = open(p, O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
	if (fd < 0)
		return false;
	struct stat locked, named;
	bool removed = fstat(fd, &locked) == 0 && S_ISREG(locked.st_mode) && flock(fd, LOCK_EX | LOCK_NB) == 0 &&
		       lstat(p, &named) == 0 && named.st_ino == locked.st_ino && named.st_dev == locked.st_dev &&
		       unlink(p) == 0;
	/* SQLite's journals of a study built in a temporary file (sty_create) go with it. */
	static const char *const side[] = {"-wal", "-shm", "-journal"};
	for (int i = 0; removed && i < 3; i++) {
		char j[TL_PATH_MAX + 16];
		snprintf(j, sizeof j, "%s%s", p, side[i]);
		unlink(j);
	}
	close(fd);
	return removed;
}

int tl_fs_clean_temps(const char *dir)
{
	DIR *d = opendir(dir);
	if (!d)
		return 0;
	int n = 0;
	struct dirent *e;
	char p[TL_PATH_MAX];
	while ((e = readdir(d)))
		if (is_temp_name(e->d_name) && snprintf(p, sizeof p, "%s/%s", dir, e->d_name) < (int)sizeof p &&
		    remove_abandoned(p))
			n++;
	closedir(d);
	return n;
}

int tl_fs_clean_temps_beside(const char *path)
{
	char dir[TL_PATH_MAX];
	if (!path || !*path)
		return 0;
	dir_of(path, dir, sizeof dir);
	return tl_fs_clean_temps(dir);
}

int tl_check_out_dir(const char *dir, const char *what, char *err, size_t err_size)
{
	int rc = tl_mkdirs(dir, err, err_size);
	if (rc)
		return rc;
	char probe[TL_PATH_MAX];
	if (snprintf(probe, sizeof probe, "%s/.taslab-probe.tmp.XXXXXX", dir) >= (int)sizeof probe)
		return tl_error(err, err_size, TL_ERR_ARG, "%s %s: path too long", what, dir);
	int fd = mkostemp(probe, O_CLOEXEC);
	if (fd < 0)
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s %s: cannot write there: %s (choose a writable %s)", what, dir,
				strerror(errno), what);
	close(fd);
	unlink(probe);
	tl_fs_clean_temps(dir);
	return TL_OK;
}

bool tl_is_dir(const char *path)
{
	struct stat sb;
	return path && stat(path, &sb) == 0 && S_ISDIR(sb.st_mode);
}

bool tl_is_file(const char *path)
{
	struct stat sb;
	return path && stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
}

bool tl_same_file(const char *a, const char *b)
{
	struct stat sa, sb;
	return a && b && stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* realpath of `p`, or of its deepest existing parent followed by the rest of the path. */
static bool resolve(const char *p, char *out)
{
	char buf[TL_PATH_MAX], rest[TL_PATH_MAX] = "";
	if (snprintf(buf, sizeof buf, "%s", p) >= (int)sizeof buf)
		return false;
	for (;;) {
		char tmp[PATH_MAX];
		if (realpath(buf, tmp)) {
			int n = snprintf(out, TL_PATH_MAX, "%s%s", tmp, rest);
			return n < TL_PATH_MAX;
		}
		char *slash = strrchr(buf, '/');
		char nrest[TL_PATH_MAX];
		if (!slash) {
			if (!getcwd(tmp, sizeof tmp))
				return false;
			snprintf(nrest, sizeof nrest, "/%s%s", buf, rest);
			return snprintf(out, TL_PATH_MAX, "%s%s", tmp, nrest) < TL_PATH_MAX;
		}
		snprintf(nrest, sizeof nrest, "%s%s", slash, rest);
		snprintf(rest, sizeof rest, "%s", nrest);
		if (slash == buf) {
			snprintf(out, TL_PATH_MAX, "%s", rest);
			return true;
		}
		*slash = 0;
	}
}

bool tl_same_path(const char *a, const char *b)
{
	return tl_same_file(a, b) || (tl_path_inside(a, b) && tl_path_inside(b, a));
}

bool tl_path_inside(const char *inner, const char *outer)
{
	char ri[TL_PATH_MAX], ro[TL_PATH_MAX];
	if (!inner || !outer || !resolve(inner, ri) || !resolve(outer, ro))
		return false;
	size_t n = strlen(ro);
	if (n == 1 && ro[0] == '/')
		return true;
	return !strncmp(ri, ro, n) && (ri[n] == 0 || ri[n] == '/');
}
