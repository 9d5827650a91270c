/* bench_study_load.c — load generator for scripts/bench-study (issue 32.3): N simulated participants answer their
 * whole session concurrently against 'taslab study serve' (GET /api/CODE/trial, POST /api/CODE/answer, one
 * keep-alive connection each), and the POST latency is measured from the request's first byte written to its
 * reply read. One thread and epoll: about 20 us of CPU a request, against about 250 us for the Node.js client
 * (tests/bench/bench_study.mjs), which on the 2-core test machine is the bottleneck of a saturation run.
 *   bench_study_load HOST PORT CODE...
 * BENCH_ADDRESSES=many: each participant from its own loopback address (127.0.x.y), as participants at home are;
 * default one address, as a lab behind one NAT. BENCH_THINK_MS=MS: a pause of 0..2 MS (seeded) before each answer.
 * Prints the lines bench_study.mjs prints (answers/s, POST p50/p99); exits 1 on any reply other than 200. */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

enum { MAX_TRIALS = 1000, BUF = 16384 };

typedef struct part {
	int fd, index;
	const char *code;
	bool posting;   /* the request in flight is the answer */
	bool waiting;   /* thinking before the answer, until wake */
	bool done;
	int trial, iter;
	double sent, wake;
	char out[512];
	size_t out_len, out_off;
	char in[BUF];
	size_t in_len;
} part;

static double now_ms(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

static unsigned long long seed = 12345;
static double rand01(void)
{
	seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
	return (double)(seed >> 11) / 9007199254740992.0;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return x < y ? -1 : x > y;
}

static _Noreturn void fail(const part *p, const char *what)
{
	fprintf(stderr, "bench_study_load: participant %s: %s\n", p ? p->code : "-", what);
	exit(1);
}

/* Writes what is left of p->out; true when all of it went. */
static bool flush_out(part *p)
{
	while (p->out_off < p->out_len) {
		ssize_t w = write(p->fd, p->out + p->out_off, p->out_len - p->out_off);
		if (w < 0 && (errno == EAGAIN || errno == EINTR))
			return false;
		if (w <= 0)
			fail(p, strerror(errno));
		p->out_off += (size_t)w;
	}
	return true;
}

static void send_request(int ep, part *p, const char *host, bool post)
{
	p->posting = post;
	if (post) {
		char body[128];
		int n = snprintf(body, sizeof body, "{\"trial\": %d, \"answer\": %d, \"rt_ms\": 1000}", p->trial,
				 (p->index + p->iter) % 5 - 2);
		p->out_len = (size_t)snprintf(p->out, sizeof p->out, "POST /api/%s/answer HTTP/1.1\r\nHost: %s\r\n"
					       "Content-Type: application/json\r\nContent-Length: %d\r\n\r\n%s", p->code, host, n,
					       body);
		p->sent = now_ms();
	} else {
		p->out_len = (size_t)snprintf(p->out, sizeof p->out, "GET /api/%s/trial HTTP/1.1\r\nHost: %s\r\n\r\n", p->code,
					       host);
	}
	p->out_off = 0;
	struct epoll_event ev = {.events = EPOLLIN | (flush_out(p) ? 0 : EPOLLOUT), .data.ptr = p};
	epoll_ctl(ep, EPOLL_CTL_MOD, p->fd, &ev);
}

/* A complete reply in p->in: its status and body (NUL-terminated in place); its length in *used. 0: not yet. */
static int parse_reply(part *p, char **body, size_t *used)
{
	p->in[p->in_len] = 0;
	char *end = strstr(p->in, "\r\n\r\n");
	if (!end)
		return 0;
	int status = 0;
	if (sscanf(p->in, "HTTP/1.%*d %d", &status) != 1)
		fail(p, "not an HTTP reply");
	long length = -1;
	for (char *l = strstr(p->in, "\r\n"); l && l < end; l = strstr(l + 2, "\r\n"))
		if (!strncasecmp(l + 2, "content-length:", 15))
			length = strtol(l + 17, NULL, 10);
	if (length < 0 || length > BUF / 2)
		fail(p, "reply without a usable Content-Length");
	size_t head = (size_t)(end + 4 - p->in);
	if (p->in_len < head + (size_t)length)
		return 0;
	*body = end + 4;
	*used = head + (size_t)length;
	return status;
}

int main(int argc, char **argv)
{
	if (argc < 4) {
		fprintf(stderr, "usage: bench_study_load HOST PORT CODE...\n");
		return 2;
	}
	const char *host = argv[1];
	int port = atoi(argv[2]), n = argc - 3;
	bool many = getenv("BENCH_ADDRESSES") && !strcmp(getenv("BENCH_ADDRESSES"), "many");
	double think = getenv("BENCH_THINK_MS") ? atof(getenv("BENCH_THINK_MS")) : 0;
	signal(SIGPIPE, SIG_IGN); /* a connection the server closed: write's error says so */
	part *ps = calloc((size_t)n, sizeof *ps);
	double *lat = malloc(sizeof *lat * (size_t)n * MAX_TRIALS);
	if (!ps || !lat)
		fail(NULL, "out of memory");
	size_t nlat = 0;
	int ep = epoll_create1(0);
	struct sockaddr_in to = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	if (inet_pton(AF_INET, host, &to.sin_addr) != 1)
		fail(NULL, "HOST must be an IPv4 address");
	double t0 = now_ms();
	for (int i = 0; i < n; i++) {
		part *p = &ps[i];
		p->code = argv[3 + i];
		p->index = i;
		p->fd = socket(AF_INET, SOCK_STREAM, 0);
		if (many) { /* 127.0.1.2, 127.0.1.3, ..., as bench_study.mjs numbers them */
			struct sockaddr_in from = {.sin_family = AF_INET};
			from.sin_addr.s_addr = htonl(0x7f000000u | (uint32_t)(1 + (i + 2) / 256) << 8 | (uint32_t)((i + 2) % 256));
			if (bind(p->fd, (struct sockaddr *)&from, sizeof from))
				fail(p, strerror(errno));
		}
		int one = 1;
		setsockopt(p->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
		if (connect(p->fd, (struct sockaddr *)&to, sizeof to) || fcntl(p->fd, F_SETFL, O_NONBLOCK))
			fail(p, strerror(errno));
		struct epoll_event ev = {.events = EPOLLIN, .data.ptr = p};
		epoll_ctl(ep, EPOLL_CTL_ADD, p->fd, &ev);
		send_request(ep, p, host, false);
	}
	int active = n;
	unsigned long acked = 0;
	struct epoll_event evs[256];
	while (active > 0) {
		double t = now_ms(), next = -1;
		for (int i = 0; i < n; i++) {
			part *p = &ps[i];
			if (!p->waiting)
				continue;
			if (p->wake <= t) {
				p->waiting = false;
				send_request(ep, p, host, true);
			} else if (next < 0 || p->wake < next) {
				next = p->wake;
			}
		}
		int k = epoll_wait(ep, evs, 256, next < 0 ? -1 : (int)(next - t) + 1);
		if (k < 0 && errno != EINTR)
			fail(NULL, strerror(errno));
		for (int e = 0; e < k; e++) {
			part *p = evs[e].data.ptr;
			if ((evs[e].events & EPOLLOUT) && flush_out(p)) {
				struct epoll_event ev = {.events = EPOLLIN, .data.ptr = p};
				epoll_ctl(ep, EPOLL_CTL_MOD, p->fd, &ev);
			}
			if (!(evs[e].events & (EPOLLIN | EPOLLHUP | EPOLLERR)))
				continue;
			if (p->in_len >= BUF - 1)
				fail(p, "a reply larger than the client's buffer");
			ssize_t r = read(p->fd, p->in + p->in_len, BUF - 1 - p->in_len);
			if (r < 0 && (errno == EAGAIN || errno == EINTR))
				continue;
			if (r <= 0)
				fail(p, r < 0 ? strerror(errno) : "connection closed by the server");
			p->in_len += (size_t)r;
			char *body;
			size_t used;
			int status = parse_reply(p, &body, &used);
			if (!status)
				continue;
			if (status != 200) {
				char why[64];
				snprintf(why, sizeof why, "HTTP %d", status);
				fail(p, why);
			}
			if (p->posting) {
				lat[nlat++] = now_ms() - p->sent;
				acked++;
				p->iter++;
				memmove(p->in, p->in + used, p->in_len - used);
				p->in_len -= used;
				if (p->iter >= MAX_TRIALS)
					fail(p, "more than 1000 trials");
				send_request(ep, p, host, false);
				continue;
			}
			json_t *j = json_loadb(body, used - (size_t)(body - p->in), 0, NULL);
			json_t *done = json_object_get(j, "done"), *idx = json_object_get(j, "index");
			if (!json_is_boolean(done) || (!json_is_true(done) && !json_is_integer(idx)))
				fail(p, "a trial reply without done / index");
			bool finished = json_is_true(done);
			p->trial = finished ? -1 : (int)json_integer_value(idx);
			json_decref(j);
			memmove(p->in, p->in + used, p->in_len - used);
			p->in_len -= used;
			if (finished) {
				epoll_ctl(ep, EPOLL_CTL_DEL, p->fd, NULL);
				close(p->fd);
				p->done = true;
				active--;
			} else if (think > 0) {
				p->waiting = true;
				p->wake = now_ms() + 2 * think * rand01();
			} else {
				send_request(ep, p, host, true);
			}
		}
	}
	double secs = (now_ms() - t0) / 1e3;
	qsort(lat, nlat, sizeof *lat, cmp_double);
	size_t i50 = nlat / 2, i99 = (size_t)(0.99 * (double)nlat);
	printf("%d participants, %lu answers acknowledged in %.2f s: %.0f answers/s\n", n, acked, secs, acked / secs);
	printf("POST /answer latency: p50 %.2f ms, p99 %.2f ms (durable commit before the reply)\n",
	       nlat ? lat[i50] : 0, nlat ? lat[i99 < nlat ? i99 : nlat - 1] : 0);
	free(lat);
	free(ps);
	close(ep);
	return 0;
}
