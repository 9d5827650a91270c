/* sweep_jobs.c — one run of a sweep (render + clip + metrics) and the local job runner that runs them N at a time,
 * each in its own process, with one progress line for the whole sweep (sweep_cli.h; DESIGN section 9).
 *
 * Why processes: a run that crashes or hits a driver fault must not take the sweep down ("one failed run is reported
 * and does not stop the others"), and a process is also the unit a Slurm array task runs, so local and cluster
 * sweeps execute exactly the same code on the same run folders. A child reports each rendered frame as one byte on a
 * pipe (TASLAB_SWEEP_PROGRESS_FD) and writes its messages to the run's log file. Children die with the parent
 * (PR_SET_PDEATHSIG), so a SIGKILLed sweep leaves no orphan rendering into a folder the next sweep redoes. */
#define _GNU_SOURCE /* prctl, pipe2 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sweep_cli.h"
#include "taslab/clip.h"
#include "taslab/colour.h"
#include "taslab/metrics_sweep.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/tl_clock.h"
#include "taslab/tl_fs.h"
#include "taslab/vkdev.h"

/* ------------------------------------------------------------------ one run (in this process) */

static void progress_byte(void *user, uint32_t done, uint32_t total)
{
	(void)done, (void)total;
	int fd = *(int *)user;
	if (fd >= 0) {
		ssize_t w = write(fd, "f", 1);
		(void)w; /* progress is best effort: a closed pipe must not fail the run */
	}
}

/* The parent folder of `path`. */
static int mkparent(const char *path, char *err, size_t err_size)
{
	char dir[TL_PATH_MAX];
	snprintf(dir, sizeof dir, "%s", path);
	char *slash = strrchr(dir, '/');
	if (!slash)
		return TL_OK;
	*slash = 0;
	return tl_mkdirs(dir, err, err_size);
}

static int render_one(const sweep_spec *s, const sweep_run *r, const char *run_dir, int progress_fd,
		      const char *command_line, char *err, size_t err_size)
{
	const sweep_scene *sc = &s->scenes[r->scene];
	const sweep_variant *v = &s->variants[r->variant];
	scene *scn = NULL;
	colour *col = NULL;
	vkdev *dev = NULL;
	method_config mc;
	int rc = method_config_parse_variant(&mc, v->variant, err, err_size);
	/* --truth: every variant whose method can count late samples does (the oracles too: their count is 0 by
	 * construction, and so is tfr's); a variant whose options exclude it (rrc --payload: no colour cached) renders
	 * without, its late column empty */
	if (!rc && s->truth && method_has_option(mc.method, "truth")) {
		method_config t = mc;
		char why[256];
		if (!method_config_set(&t, "truth", NULL, why, sizeof why) && !method_config_check(&t, why, sizeof why))
			mc = t;
	}
	if (!rc)
		rc = scene_load(sc->path, &scn, err, err_size);
	int cam = scn ? scene_find_camera(scn, sc->cameras[r->camera].name) : -1;
	if (!rc && cam < 0)
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s has no camera path '%s' any more", sc->path,
			      sc->cameras[r->camera].name);
	/* the inputs the sweep was resolved from, by content: a run of an edited scene (or asset) is never mixed into a
	 * sweep of the old one (issue 31.4) */
	char digest[SCENE_DIGEST_HEX > COLOUR_DIGEST_HEX ? SCENE_DIGEST_HEX : COLOUR_DIGEST_HEX];
	if (!rc) {
		scene_digest(scn, digest);
		if (strcmp(digest, sc->digest))
			rc = tl_error(err, err_size, TL_ERR_INPUT,
				      "%s or one of its assets changed since the sweep was resolved (content digest %s, the sweep's "
				      "%s): start a new sweep (another --out) for the changed scene",
				      sc->path, digest, sc->digest[0] ? sc->digest : "none");
	}
	colour_desc cd = {.config_path = s->ocio_config[0] ? s->ocio_config : NULL, .display = s->display[0] ? s->display : NULL,
			  .view = s->view[0] ? s->view : NULL};
	if (!rc)
		rc = colour_create(&cd, &col, err, err_size);
	if (!rc && strcmp(colour_name(col), s->display_transform))
		rc = tl_error(err, err_size, TL_ERR_INPUT, "the display transform is now '%s', the sweep's is '%s'",
			      colour_name(col), s->display_transform);
	if (!rc) {
		colour_digest(col, digest);
		if (strcmp(digest, s->colour_digest))
			rc = tl_error(err, err_size, TL_ERR_INPUT,
				      "the OpenColorIO config or one of its LUTs changed since the sweep was resolved (content "
				      "digest %s, the sweep's %s): start a new sweep (another --out)",
				      digest, s->colour_digest[0] ? s->colour_digest : "none");
	}
	vkdev_desc dd = {.device = s->device[0] ? s->device : NULL, .validation = s->validation};
	if (!rc && vkdev_create(&dd, &dev, err, err_size))
		rc = TL_ERR_VULKAN;
	if (!rc)
		rc = mkparent(run_dir, err, err_size);
	if (!rc) {
		fprintf(stderr, "taslab sweep: rendering %s/%s %s on %s, frames %u..%u at %ux%u%s\n", sc->name,
			sc->cameras[r->camera].name, v->variant, dev->props.deviceName, sc->first, sc->end - 1, s->width,
			s->height, s->stereo ? " per eye, stereo" : "");
		render_run_desc rr = {.dev = dev, .scene = scn, .scene_path = sc->path, .camera = cam, .colour = col,
				      .method = &mc, .first = sc->first, .end = sc->end, .width = s->width, .height = s->height,
				      .fps = (float)sc->fps, .write_exr = true, .write_png = true, .out = run_dir,
				      .command_line = command_line, .progress = progress_byte, .user = &progress_fd,
				      .views = s->stereo ? 2 : 1, .ipd = (float)s->ipd};
		rc = render_run(&rr, err, err_size);
	}
	if (!rc && dev && vkdev_validation_messages(dev))
		rc = tl_error(err, err_size, TL_ERR_VALIDATION, "%u Vulkan validation message(s) (printed above)",
			      vkdev_validation_messages(dev));
	vkdev_destroy(&dev);
	colour_destroy(&col);
	scene_destroy(&scn);
	return rc;
}

int cli_sweep_flock(const char *path, int *fd, char *err, size_t err_size)
{
	*fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
	if (*fd < 0)
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: %s", path, strerror(errno));
	if (flock(*fd, LOCK_EX | LOCK_NB)) {
		int e = errno;
		close(*fd);
		*fd = -1;
		if (e == EWOULDBLOCK)
			return TL_ERR_CONFLICT;
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot lock: %s", path, strerror(e));
	}
	return TL_OK;
}

static int task_run(const sweep_spec *s, const char *dir, size_t index, int progress_fd, const char *command_line,
		    bool *deferred, char *err, size_t err_size);

/* One run, under SWEEP/.taslab-locks/I (review finding, 2026-11-27): the sweep's folder lock keeps a second sweep out,
 * but not a second process for the same run - `--task I` by hand beside a running sweep, or a Slurm array task requeued
 * while the first still ran - and two processes rendering one run write the same files. The second is refused. */
int cli_sweep_task(const sweep_spec *s, const char *dir, size_t index, int progress_fd, const char *command_line,
		   bool *deferred, char *err, size_t err_size)
{
	char p[TL_PATH_MAX + 64];
	int fd = -1;
	snprintf(p, sizeof p, "%s/.taslab-locks", dir);
	if (mkdir(p, 0755) && errno != EEXIST)
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: %s", p, strerror(errno));
	snprintf(p, sizeof p, "%s/.taslab-locks/%zu", dir, index);
	int rc = cli_sweep_flock(p, &fd, err, err_size);
	if (rc == TL_ERR_CONFLICT)
		return tl_error(err, err_size, TL_ERR_CONFLICT,
				"run %zu: another process is doing this run (it holds %s): nothing done", index, p);
	if (!rc)
		rc = task_run(s, dir, index, progress_fd, command_line, deferred, err, err_size);
	if (fd >= 0)
		close(fd);
	return rc;
}

static int task_run(const sweep_spec *s, const char *dir, size_t index, int progress_fd, const char *command_line,
		    bool *deferred, char *err, size_t err_size)
{
	sweep_run r, ref;
	sweep_status st, ref_st;
	char run_dir[TL_PATH_MAX], clip[TL_PATH_MAX], metrics[TL_PATH_MAX], p[TL_PATH_MAX + 16];
	*deferred = false;
	if (sweep_run_at(s, index, &r))
		return tl_error(err, err_size, TL_ERR_ARG, "--task %zu: the sweep has runs 0..%zu", index, sweep_run_count(s) - 1);
	sweep_run_path(s, dir, &r, SWEEP_PATH_RUN, run_dir, sizeof run_dir);
	sweep_run_path(s, dir, &r, SWEEP_PATH_CLIP, clip, sizeof clip);
	sweep_run_path(s, dir, &r, SWEEP_PATH_METRICS, metrics, sizeof metrics);
	char why[1024];
	sweep_run_status_checked(s, dir, &r, &st, why, sizeof why);
	if (st.damaged) /* never re-rendered behind the user's back, never read: the sweep lists it (issue 31.8) */
		return tl_error(err, err_size, TL_ERR_INPUT, "%s (a damaged run: 'taslab sweep %s/sweep.json --redo-damaged' "
			        "renders it again)", why, dir);
	int rc = TL_OK;
	double t0 = tl_clock_s();
	if (!st.run) {
		/* A run being (re)rendered invalidates what was made from an earlier attempt. */
		snprintf(p, sizeof p, "%s/summary.json", metrics);
		unlink(clip);
		unlink(p);
		if ((rc = render_one(s, &r, run_dir, progress_fd, command_line, err, err_size)))
			return rc;
		fprintf(stderr, "taslab sweep: rendered in %.2f s\n", tl_clock_s() - t0);
	}
	if (!st.clip || !st.run) {
		uint32_t n;
		double t1 = tl_clock_s();
		if ((rc = mkparent(clip, err, err_size)) || (rc = clip_encode_run(run_dir, clip, &n, err, err_size)))
			return rc;
		fprintf(stderr, "taslab sweep: clip of %u frames in %.2f s\n", n, tl_clock_s() - t1);
	}
	sweep_run_status(s, dir, &r, &st);
	if (st.metrics)
		return TL_OK;
	sweep_run_at(s, r.ref_index, &ref);
	sweep_run_status_checked(s, dir, &ref, &ref_st, why, sizeof why);
	if (ref_st.damaged)
		return tl_error(err, err_size, TL_ERR_INPUT, "its ref run is damaged: %s", why);
	if (!ref_st.run) {
		*deferred = true; /* the ref run is not complete yet: compared later (local runner or report job) */
		fprintf(stderr, "taslab sweep: %s: the ref run is not complete yet; its metrics are computed later\n", run_dir);
		return TL_OK;
	}
	double t2 = tl_clock_s();
	if ((rc = mtr_sweep_metrics(s, dir, &r, 0, err, err_size)))
		return rc;
	fprintf(stderr, "taslab sweep: metrics against ref in %.2f s\n", tl_clock_s() - t2);
	return TL_OK;
}

/* ------------------------------------------------------------------ the local job runner */

int cli_sweep_self(char *out, size_t out_size, char *err, size_t err_size)
{
	ssize_t n = readlink("/proc/self/exe", out, out_size - 1);
	if (n <= 0)
		return tl_error(err, err_size, TL_ERR_INTERNAL, "cannot find the taslab binary (/proc/self/exe)");
	out[n] = 0;
	return TL_OK;
}

typedef struct job {
	pid_t pid;
	int fd;             /* progress pipe (read end), -1 when closed */
	size_t index;
	uint32_t frames;    /* rendered so far */
	uint32_t total;     /* frames of the run (0: nothing to render) */
} job;

static volatile sig_atomic_t stop_signal;

static void on_signal(int sig) { stop_signal = sig; }

static void fmt_time(double s, char *out, size_t n)
{
	if (!isfinite(s) || s < 0)
		snprintf(out, n, "?");
	else if (s < 60)
		snprintf(out, n, "%.0fs", s);
	else if (s < 3600)
		snprintf(out, n, "%dm%02ds", (int)s / 60, (int)s % 60);
	else
		snprintf(out, n, "%dh%02dm", (int)s / 3600, ((int)s % 3600) / 60);
}

extern char **environ;

/* The child's environment: ours plus the progress descriptor (built before fork: the child only calls exec). */
static char **child_env(void)
{
	size_t n = 0;
	while (environ[n])
		n++;
	char **env = calloc(n + 2, sizeof *env);
	if (!env)
		return NULL;
	size_t k = 0;
	for (size_t i = 0; i < n; i++)
		if (strncmp(environ[i], "TASLAB_SWEEP_PROGRESS_FD=", 25))
			env[k++] = environ[i];
	env[k++] = "TASLAB_SWEEP_PROGRESS_FD=3";
	env[k] = NULL;
	return env;
}

static int spawn(const sweep_spec *s, const char *dir, const char *self, char **env, size_t index, job *j, char *err,
		 size_t err_size)
{
	sweep_run r;
	char log[TL_PATH_MAX], spec[TL_PATH_MAX], idx[32];
	sweep_run_at(s, index, &r);
	sweep_run_path(s, dir, &r, SWEEP_PATH_LOG, log, sizeof log);
	int rc = mkparent(log, err, err_size);
	if (rc)
		return rc;
	snprintf(spec, sizeof spec, "%s/sweep.json", dir);
	snprintf(idx, sizeof idx, "%zu", index);
	int pfd[2];
	if (pipe2(pfd, O_CLOEXEC))
		return tl_error(err, err_size, TL_ERR_OUTPUT, "pipe: %s", strerror(errno));
	fcntl(pfd[0], F_SETFL, O_NONBLOCK);
	int logfd = open(log, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
	if (logfd < 0) {
		close(pfd[0]), close(pfd[1]);
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: %s", log, strerror(errno));
	}
	pid_t parent = getpid();
	pid_t pid = fork();
	if (pid < 0) {
		close(pfd[0]), close(pfd[1]), close(logfd);
		return tl_error(err, err_size, TL_ERR_OUTPUT, "fork: %s", strerror(errno));
	}
	if (pid == 0) {
		/* child: only async-signal-safe calls until exec */
		prctl(PR_SET_PDEATHSIG, SIGKILL);
		if (getppid() != parent)
			_exit(127);
		int devnull = open("/dev/null", O_RDWR);
		dup2(devnull, 0);
		dup2(logfd, 1);
		dup2(logfd, 2);
		dup2(pfd[1], 3);
		char *argv[] = {"taslab", "sweep", spec, "--task", idx, NULL};
		execve(self, argv, env);
		_exit(127);
	}
	close(pfd[1]);
	close(logfd);
	*j = (job){.pid = pid, .fd = pfd[0], .index = index};
	return TL_OK;
}

/* The last non-empty line of a run's log: the child's one-line error. */
static void last_line(const char *path, char *out, size_t n)
{
	char *text = NULL, err[64];
	size_t len = 0;
	out[0] = 0;
	if (tl_read_file(path, 16u << 20, &text, &len, err, sizeof err))
		return;
	while (len && (text[len - 1] == '\n' || text[len - 1] == '\r'))
		text[--len] = 0;
	char *l = strrchr(text, '\n');
	snprintf(out, n, "%s", l ? l + 1 : text);
	free(text);
}

static void label(const sweep_spec *s, size_t index, char *out, size_t n)
{
	sweep_run r;
	sweep_run_at(s, index, &r);
	snprintf(out, n, "%s/%s/%s", s->scenes[r.scene].name, s->scenes[r.scene].cameras[r.camera].name,
		 s->variants[r.variant].id);
}

int cli_sweep_local(const sweep_spec *s, const char *dir, unsigned jobs, bool quiet, size_t *failed_out, char *err,
		    size_t err_size)
{
	size_t n = sweep_run_count(s);
	size_t *queue = calloc(3 * n + 1, sizeof *queue), qhead = 0, qtail = 0;
	bool *failed = calloc(n + 1, sizeof *failed), *requeued = calloc(n + 1, sizeof *requeued);
	job *active = calloc(jobs ? jobs : 1, sizeof *active);
	char **env = child_env();
	char self[TL_PATH_MAX];
	int rc = queue && failed && requeued && active && env ? TL_OK : tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	if (!rc)
		rc = cli_sweep_self(self, sizeof self, err, err_size);
	if (rc)
		goto done;
	/* What is to do: every run without run, clip or metrics. Frames count only for runs still to render. */
	size_t done_runs = 0, failed_runs = 0, nactive = 0, todo = 0;
	uint64_t frames_todo = 0, frames_done = 0;
	for (size_t i = 0; i < n; i++) {
		sweep_run r;
		sweep_status st;
		char why[1024];
		sweep_run_at(s, i, &r);
		sweep_run_status_checked(s, dir, &r, &st, why, sizeof why);
		if (st.run && st.clip && st.metrics) {
			done_runs++;
			continue;
		}
		if (st.damaged) { /* listed once by the sweep (cmd_sweep.c): failed, not retried behind the user's back */
			failed[i] = true;
			failed_runs++;
			continue;
		}
		queue[qtail++] = i;
		todo++;
		if (!st.run)
			frames_todo += s->scenes[r.scene].end - s->scenes[r.scene].first;
	}
	if (!quiet)
		fprintf(stderr, "taslab sweep: %zu runs, %zu complete, %zu to do (%llu frames to render), %u at a time\n", n,
			done_runs, todo, (unsigned long long)frames_todo, jobs);
	struct sigaction sa = {.sa_handler = on_signal}, old_int, old_term;
	sigemptyset(&sa.sa_mask);
	sigaction(SIGINT, &sa, &old_int);
	sigaction(SIGTERM, &sa, &old_term);
	stop_signal = 0;
	double t0 = tl_clock_s(), last_print = 0;
	int tty = isatty(2);
	bool dirty = true;
	while ((qhead < qtail || nactive) && !rc) {
		while (!stop_signal && nactive < jobs && qhead < qtail) {
			/* the first entry that can go: one to render, or a comparison whose ref run is done (or failed) */
			size_t pick = qtail;
			for (size_t q = qhead; q < qtail && pick == qtail; q++) {
				sweep_run r, ref;
				sweep_status st, ref_st;
				sweep_run_at(s, queue[q], &r);
				sweep_run_status(s, dir, &r, &st);
				sweep_run_at(s, r.ref_index, &ref);
				sweep_run_status(s, dir, &ref, &ref_st);
				if (!st.run || r.is_ref || ref_st.run || failed[r.ref_index])
					pick = q;
			}
			if (pick == qtail) {
				if (nactive)
					break; /* comparisons wait for their ref runs */
				pick = qhead; /* nothing runs that could complete a ref: let it report */
			}
			size_t i = queue[pick];
			memmove(&queue[qhead + 1], &queue[qhead], (pick - qhead) * sizeof *queue);
			queue[qhead++] = i;
			job *j = &active[nactive];
			sweep_run r;
			sweep_status st;
			sweep_run_at(s, i, &r);
			sweep_run_status(s, dir, &r, &st);
			if ((rc = spawn(s, dir, self, env, i, j, err, err_size)))
				break;
			j->total = st.run ? 0 : s->scenes[r.scene].end - s->scenes[r.scene].first;
			nactive++;
			dirty = true;
			if (!quiet && !tty) {
				char l[256];
				label(s, i, l, sizeof l);
				fprintf(stderr, "taslab sweep: start %s%s\n", l, st.run ? " (clip/metrics)" : "");
			}
		}
		if (rc || (stop_signal && !nactive))
			break;
		struct pollfd pf[256];
		size_t np = 0;
		for (size_t k = 0; k < nactive && np < 256; k++)
			if (active[k].fd >= 0)
				pf[np++] = (struct pollfd){.fd = active[k].fd, .events = POLLIN};
		if (poll(pf, np, np ? 250 : 50) < 0 && errno != EINTR) {
			rc = tl_error(err, err_size, TL_ERR_INTERNAL, "poll: %s", strerror(errno));
			break;
		}
		for (size_t k = 0; k < nactive; k++) {
			job *j = &active[k];
			if (j->fd < 0)
				continue;
			char buf[256];
			ssize_t got;
			while ((got = read(j->fd, buf, sizeof buf)) > 0)
				j->frames += (uint32_t)got, frames_done += (uint64_t)got, dirty = true;
			if (got == 0 || (got < 0 && errno != EAGAIN && errno != EINTR)) {
				close(j->fd);
				j->fd = -1;
			}
			if (got < 0 && errno == EAGAIN)
				continue;
		}
		if (stop_signal)
			for (size_t k = 0; k < nactive; k++)
				kill(active[k].pid, SIGTERM);
		/* reap finished children */
		for (size_t k = 0; k < nactive;) {
			job *j = &active[k];
			int status;
			pid_t w = waitpid(j->pid, &status, WNOHANG);
			if (w == 0) {
				k++;
				continue;
			}
			if (j->fd >= 0) {
				char buf[256];
				ssize_t got;
				while ((got = read(j->fd, buf, sizeof buf)) > 0)
					frames_done += (uint64_t)got;
				close(j->fd);
			}
			sweep_run r, ref;
			sweep_status st, ref_st;
			sweep_run_at(s, j->index, &r);
			sweep_run_status(s, dir, &r, &st);
			sweep_run_at(s, r.ref_index, &ref);
			sweep_run_status(s, dir, &ref, &ref_st);
			char l[256], log[TL_PATH_MAX], why[1024];
			label(s, j->index, l, sizeof l);
			sweep_run_path(s, dir, &r, SWEEP_PATH_LOG, log, sizeof log);
			bool exited_ok = w > 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0;
			bool complete = st.run && st.clip && st.metrics;
			/* run and clip done, the comparison not: its ref run was still rendering. It waits in the queue until
			 * the ref is complete; a comparison missing with the ref complete gets one more try. */
			bool waits = exited_ok && !complete && st.run && st.clip && !stop_signal && !failed[r.ref_index] &&
				     !(ref_st.run && requeued[j->index]);
			if (waits) {
				requeued[j->index] |= ref_st.run;
				queue[qtail++] = j->index;
			} else if (exited_ok && complete) {
				done_runs++;
				if (!quiet && !tty)
					fprintf(stderr, "taslab sweep: done %s\n", l);
			} else if (!stop_signal) {
				if (exited_ok && !ref_st.run)
					snprintf(why, sizeof why, "no metrics: its ref run did not complete");
				else if (exited_ok)
					snprintf(why, sizeof why, "its clip or metrics are missing after the run (see the log)");
				else if (w > 0 && WIFSIGNALED(status))
					snprintf(why, sizeof why, "killed by signal %d", WTERMSIG(status));
				else
					last_line(log, why, sizeof why);
				failed[j->index] = true;
				failed_runs++;
				if (tty && !quiet)
					fputs("\r\033[K", stderr);
				fprintf(stderr, "taslab sweep: %s failed: %s (log: %s)\n", l, why, log);
			}
			active[k] = active[--nactive];
			dirty = true;
		}
		/* the progress line: runs, frames, elapsed, ETA, and each running run's frames */
		double now = tl_clock_s();
		if (!quiet && dirty && (tty ? now - last_print > 0.2 : now - last_print > 30 || !nactive)) {
			char line[2048], el[32], eta[32];
			double elapsed = now - t0;
			fmt_time(elapsed, el, sizeof el);
			fmt_time(frames_done ? elapsed / (double)frames_done * ((double)frames_todo - (double)frames_done) : NAN, eta,
				 sizeof eta);
			char fails[64] = "";
			if (failed_runs)
				snprintf(fails, sizeof fails, ", %zu failed", failed_runs);
			int len = snprintf(line, sizeof line, "sweep: %zu/%zu runs%s | %llu/%llu frames | %s elapsed, ETA %s",
					   done_runs, n, fails, (unsigned long long)frames_done, (unsigned long long)frames_todo,
					   el, frames_done < frames_todo ? eta : "0s");
			for (size_t k = 0; k < nactive && len < (int)sizeof line - 128; k++) {
				char l[256];
				label(s, active[k].index, l, sizeof l);
				len += active[k].total
					       ? snprintf(line + len, sizeof line - (size_t)len, " | %s %u/%u", l, active[k].frames,
							  active[k].total)
					       : snprintf(line + len, sizeof line - (size_t)len, " | %s clip/metrics", l);
			}
			fprintf(stderr, tty ? "\r\033[K%s" : "taslab %s\n", line);
			fflush(stderr);
			last_print = now;
			dirty = false;
		}
	}
	if (tty && !quiet)
		fputc('\n', stderr);
	/* stop whatever still runs (an error or a signal) */
	for (size_t k = 0; k < nactive; k++) {
		kill(active[k].pid, SIGTERM);
		waitpid(active[k].pid, NULL, 0);
		if (active[k].fd >= 0)
			close(active[k].fd);
	}
	sigaction(SIGINT, &old_int, NULL);
	sigaction(SIGTERM, &old_term, NULL);
	if (!rc && stop_signal)
		rc = tl_error(err, err_size, TL_ERR_INTERRUPTED,
			      "interrupted (signal %d): %zu of %zu runs complete; run the same command again to resume",
			      (int)stop_signal, done_runs, n);
	*failed_out = failed_runs;
done:
	free(queue);
	free(failed);
	free(requeued);
	free(active);
	free(env);
	return rc;
}
