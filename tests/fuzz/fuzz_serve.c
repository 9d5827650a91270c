/* fuzz_serve.c — libFuzzer harness for the study server's request handling (untrusted input: anything a browser
 * or an attacker sends). It drives sty_server_handle, the socket-free core behind the libmicrohttpd adapter, with
 * a real study (SQLite, 2 participants, small clip files) made once in a private folder.
 *
 * Input format (text):   METHOD PATH\n  Name: value\n ...  \n  BODY
 * i.e. a request line, header lines up to an empty line, then the body (may be empty or binary). Placeholders let
 * the fuzzer reach past the unguessable names: {code} and {code2} (participant link codes), {clip} / {clipb}
 * (/clips/<name> of the first participant's current trial), {token} (the admin token).
 *
 * Properties checked beyond "no crash, leak or hang" (ASan + UBSan via scripts/fuzz serve):
 *   - every request gets a status in 200..599, and never 500 (the study is healthy, so a 500 is a bug);
 *   - no error response names the server's folder;
 *   - an export (200 on /admin/...) needs the {token}, a clip needs a {clip} name (names are not guessable);
 *   - a file response lies inside its file, and a 206 says which part.
 * Answers stored by one input are deleted before the next, so inputs do not depend on each other. */
#define _GNU_SOURCE /* mkdtemp, nftw, memmem */
#include <sqlite3.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/study.h"
#include "taslab/study_serve.h"
#include "../test_study_methods.h"
#include "fuzz_tmp.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char code[2][40], clip[2][64], token[40];
static sty *study;
static sty_server *server;
static sqlite3 *side; /* resets the answers between inputs */

static void cleanup(void)
{
	sty_server_stop(&server);
	sty_close(&study);
	sqlite3_close(side);
	fuzz_tmp_remove();
}

static void quiet(void *cls, const char *line) { (void)cls, (void)line; }

static void write_file(const char *path, const char *text)
{
	FILE *f = fopen(path, "w");
	if (!f || fputs(text, f) < 0 || fclose(f))
		abort();
}

/* Two sets (stationary and moving) with tfr@8, tfr@16, rrc/4 and rrc/8 (variants with a period), a study of 2
 * participants with training, catch trials and breaks, the server (not listening), and the placeholders' values. */
static void setup(void)
{
	fuzz_tmp_make("serve", cleanup);
	char p[512], stim[300], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", fuzz_dir);
	mkdir(stim, 0755);
	const char *sets[2][2] = {{"still", "stationary"}, {"walk", "moving"}};
	for (int i = 0; i < 2; i++) {
		snprintf(p, sizeof p, "%s/%s", stim, sets[i][0]);
		mkdir(p, 0755);
		const char *clips[5] = {"ref", "tfr8", "tfr16", "rrc4", "rrc8"};
		for (int c = 0; c < 5; c++) {
			snprintf(p, sizeof p, "%s/%s/%s.webm", stim, sets[i][0], clips[c]);
			char text[128];
			snprintf(text, sizeof text, "clip %s of %s: 0123456789abcdefghijklmnopqrstuvwxyz", clips[c], sets[i][0]);
			write_file(p, text);
		}
		snprintf(p, sizeof p, "%s/%s/pairs.json", stim, sets[i][0]);
		char json[1024];
		snprintf(json, sizeof json,
			 "{\"taslab_pairs\": 1, \"scene\": \"calm\", \"camera\": \"%s\", \"camera_motion\": \"%s\", \"fps\": 60,"
			 " \"frames\": [0, 59], \"reference\": {\"clip\": \"ref.webm\"}, \"conditions\": ["
			 "{\"method\": \"tfr\", \"T\": 8, \"clip\": \"tfr8.webm\"}, {\"method\": \"tfr\", \"T\": 16, \"clip\": \"tfr16.webm\"},"
			 " {\"method\": \"rrc\", \"period\": 4, \"clip\": \"rrc4.webm\"}, {\"method\": \"rrc\", \"period\": 8, \"clip\": \"rrc8.webm\"}]}",
			 sets[i][0], sets[i][1]);
		write_file(p, json);
	}
	snprintf(p, sizeof p, "%s/study.db", stim); /* kept among the stimuli: it must never be served */
	sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 7, .training = 1, .catch_trials = 1, .break_every = 2};
	sty_design_summary sm;
	if (sty_create(p, &study, err, sizeof err) || tu_describe_methods(study) ||
	    sty_design(study, &d, &sm, err, sizeof err) ||
	    sty_commit(study, err, sizeof err)) {
		fprintf(stderr, "fuzz_serve: %s\n", err);
		abort();
	}
	sty_server_desc sd = {.log = quiet};
	if (sty_server_create(study, &sd, &server, err, sizeof err))
		abort();
	char **codes;
	size_t n;
	if (sty_participant_codes(study, &codes, &n, err, sizeof err) || n != 2)
		abort();
	for (size_t i = 0; i < n; i++) {
		snprintf(code[i], sizeof code[i], "%s", codes[i]);
		free(codes[i]);
	}
	free(codes);
	sty_trial t;
	if (sty_next_trial(study, code[0], &t, err, sizeof err))
		abort();
	snprintf(clip[0], sizeof clip[0], "/clips/%s", t.clip_a);
	snprintf(clip[1], sizeof clip[1], "/clips/%s", t.clip_b);
	snprintf(token, sizeof token, "%s", sty_admin_token(study));
	if (sqlite3_open(p, &side) != SQLITE_OK)
		abort();
	sqlite3_busy_timeout(side, 5000);
}

/* The input with the placeholders replaced (malloc'ed, NUL-terminated; *len without the NUL). */
static char *substitute(const uint8_t *data, size_t size, size_t *len)
{
	const char *keys[5] = {"{code}", "{code2}", "{clip}", "{clipb}", "{token}"};
	const char *vals[5] = {code[0], code[1], clip[0], clip[1], token};
	char *out = malloc(size * 12 + 1); /* every value is at most 12 x its key */
	size_t k = 0;
	for (size_t i = 0; i < size;) {
		int hit = 0;
		for (int j = 0; j < 5 && !hit; j++) {
			size_t kl = strlen(keys[j]);
			if (size - i >= kl && !memcmp(data + i, keys[j], kl)) {
				memcpy(out + k, vals[j], strlen(vals[j]));
				k += strlen(vals[j]);
				i += kl;
				hit = 1;
			}
		}
		if (!hit)
			out[k++] = (char)data[i++];
	}
	out[k] = 0;
	*len = k;
	return out;
}

static void check(const sty_request *rq, const sty_response *r, const uint8_t *data, size_t size)
{
	if (r->status < 200 || r->status > 599 || r->status == 500 || !r->content_type)
		__builtin_trap();
	if (r->body && r->status >= 400 && strstr(r->body, fuzz_dir))
		__builtin_trap(); /* an error names a server path */
	int with_token = memmem(data, size, "{token}", 7) != NULL, with_clip = memmem(data, size, "{clip", 5) != NULL;
	const char *path = rq->path ? rq->path : "";
	if (r->status == 200 && !strncmp(path, "/admin/", 7) && !with_token)
		__builtin_trap();
	if ((r->status == 200 || r->status == 206 || r->status == 416) && !strncmp(path, "/clips/", 7) && !with_clip)
		__builtin_trap();
	if (r->fd >= 0) {
		struct stat sb;
		if (fstat(r->fd, &sb) || r->file_offset + r->file_size > (uint64_t)sb.st_size)
			__builtin_trap();
		if ((r->status == 206) != (r->content_range[0] != 0))
			__builtin_trap();
	}
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	if (!study)
		setup();
	size_t len;
	char *text = substitute(data, size, &len);
	/* Request line. */
	char *line_end = memchr(text, '\n', len), *p = text;
	char *end = text + len;
	char *rl_end = line_end ? line_end : end;
	*rl_end = 0;
	char *method = p, *path = strchr(p, ' ');
	if (path)
		*path++ = 0;
	else
		path = "/";
	if (rl_end > p && rl_end[-1] == '\r')
		rl_end[-1] = 0;
	/* Header lines up to an empty line; the rest is the body. */
	sty_http_field fields[64];
	size_t nf = 0;
	const char *body = "";
	size_t body_size = 0;
	p = rl_end < end ? rl_end + 1 : end;
	while (p < end) {
		char *nl = memchr(p, '\n', (size_t)(end - p));
		char *le = nl ? nl : end;
		*le = 0;
		if (le > p && le[-1] == '\r')
			le[-1] = 0;
		if (!*p) { /* the empty line */
			body = nl ? nl + 1 : end;
			body_size = (size_t)(end - body);
			break;
		}
		char *colon = strchr(p, ':');
		if (nf < 64) {
			if (colon) {
				*colon = 0;
				char *v = colon + 1;
				while (*v == ' ' || *v == '\t')
					v++;
				fields[nf++] = (sty_http_field){p, v};
			} else {
				fields[nf++] = (sty_http_field){p, ""};
			}
		}
		p = nl ? nl + 1 : end;
	}
	sty_request rq = {.method = method, .path = path, .headers = fields, .header_count = nf};
	sty_response r;
	sty_server_handle(server, &rq, &r); /* the head first, as the adapter does */
	if (r.status == 0) {
		if (body_size > STY_MAX_BODY_B) {
			rq.body_too_large = true;
			body_size = 0;
		}
		rq.body = body;
		rq.body_size = body_size;
		sty_server_handle(server, &rq, &r);
	}
	if (getenv("FUZZ_SERVE_VERBOSE")) /* to see what the seeds reach: FUZZ_SERVE_VERBOSE=1 fuzz_serve FILE... */
		fprintf(stderr, "%s %s -> %u %.100s\n", method, path, r.status, r.body ? r.body : "(file)");
	check(&rq, &r, data, size);
	sty_response_release(&r);
	free(text);
	if (sqlite3_exec(side, "DELETE FROM answers", NULL, NULL, NULL) != SQLITE_OK)
		abort();
	return 0;
}
