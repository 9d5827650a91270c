/* clip.c — lossless VP9 / gbrp / WebM clips through libavcodec and libavformat (see clip.h). */
#include "taslab/clip.h"

#include <errno.h>
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/opt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/imageio.h"
#include "taslab/run.h"
#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"

struct clip_writer {
	tl_atomic file; /* the clip is written to file.tmp and committed by clip_writer_finish */
	AVFormatContext *fmt;
	AVCodecContext *enc;
	AVStream *st;
	AVFrame *frame;
	AVPacket *pkt;
	int64_t next_pts;
	int header_written;
};

static void av_err(char *err, size_t err_size, const char *what, int code)
{
	char buf[AV_ERROR_MAX_STRING_SIZE] = "";
	av_strerror(code, buf, sizeof buf);
	snprintf(err, err_size, "%s: %s", what, buf);
}

int clip_writer_create(const char *path, uint32_t width, uint32_t height, double fps, clip_writer **out, char *err,
		       size_t err_size)
{
	*out = NULL;
	int r;
	clip_writer *w = calloc(1, sizeof *w);
	if (!w) {
		snprintf(err, err_size, "out of memory");
		return TL_ERR_OUTPUT;
	}
	tl_fs_clean_temps_beside(path); /* clips of killed encoders */
	int rc = tl_atomic_open(&w->file, path, err, err_size);
	if (rc || (rc = tl_atomic_detach(&w->file, err, err_size))) {
		free(w);
		return rc;
	}
	rc = TL_ERR_OUTPUT;
	av_log_set_level(AV_LOG_ERROR); /* libvpx announces its version at info level */
	const AVCodec *codec = avcodec_find_encoder_by_name("libvpx-vp9");
	if (!codec) {
		snprintf(err, err_size, "libavcodec has no libvpx-vp9 encoder (install Debian's libavcodec59 with libvpx)");
		rc = TL_ERR_UNSUPPORTED;
		goto fail;
	}
	if ((r = avformat_alloc_output_context2(&w->fmt, NULL, "webm", w->file.tmp)) < 0) {
		av_err(err, err_size, "cannot create a WebM muxer", r);
		goto fail;
	}
	w->enc = avcodec_alloc_context3(codec);
	w->frame = av_frame_alloc();
	w->pkt = av_packet_alloc();
	w->st = avformat_new_stream(w->fmt, NULL);
	if (!w->enc || !w->frame || !w->pkt || !w->st) {
		snprintf(err, err_size, "out of memory");
		goto fail;
	}
	AVRational rate = av_d2q(fps, 100000);
	w->enc->width = (int)width;
	w->enc->height = (int)height;
	w->enc->pix_fmt = AV_PIX_FMT_GBRP;
	w->enc->time_base = av_inv_q(rate);
	w->enc->framerate = rate;
	w->enc->gop_size = 60;
	w->enc->thread_count = 2;
	/* Full-range RGB, sRGB transfer: what the PNG frames hold, tagged so players do no conversion. */
	w->enc->color_range = AVCOL_RANGE_JPEG;
	w->enc->colorspace = AVCOL_SPC_RGB;
	w->enc->color_primaries = AVCOL_PRI_BT709;
	w->enc->color_trc = AVCOL_TRC_IEC61966_2_1;
	if (w->fmt->oformat->flags & AVFMT_GLOBALHEADER)
		w->enc->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
	av_opt_set_int(w->enc->priv_data, "lossless", 1, 0);
	av_opt_set_int(w->enc->priv_data, "row-mt", 1, 0);
	/* Lossless either way; the fastest preset encodes ~3.5x faster than "good"/4 for ~10% larger files
	 * (scripts/bench-clip). */
	av_opt_set_int(w->enc->priv_data, "cpu-used", 8, 0);
	av_opt_set(w->enc->priv_data, "deadline", "realtime", 0);
	if ((r = avcodec_open2(w->enc, codec, NULL)) < 0) {
		av_err(err, err_size, "cannot open the VP9 encoder", r);
		goto fail;
	}
	if ((r = avcodec_parameters_from_context(w->st->codecpar, w->enc)) < 0) {
		av_err(err, err_size, "codec parameters", r);
		goto fail;
	}
	w->st->time_base = w->enc->time_base;
	w->st->avg_frame_rate = rate;
	if ((r = avio_open(&w->fmt->pb, w->file.tmp, AVIO_FLAG_WRITE)) < 0) {
		av_err(err, err_size, path, r);
		goto fail;
	}
	if ((r = avformat_write_header(w->fmt, NULL)) < 0) {
		av_err(err, err_size, "cannot write the WebM header", r);
		goto fail;
	}
	w->header_written = 1;
	w->frame->format = AV_PIX_FMT_GBRP;
	w->frame->width = (int)width;
	w->frame->height = (int)height;
	if ((r = av_frame_get_buffer(w->frame, 0)) < 0) {
		av_err(err, err_size, "frame buffer", r);
		goto fail;
	}
	*out = w;
	return TL_OK;
fail:
	clip_writer_destroy(&w);
	return rc;
}

static int drain(clip_writer *w, char *err, size_t err_size)
{
	for (;;) {
		int r = avcodec_receive_packet(w->enc, w->pkt);
		if (r == AVERROR(EAGAIN) || r == AVERROR_EOF)
			return 0;
		if (r < 0) {
			av_err(err, err_size, "VP9 encoding failed", r);
			return TL_ERR_OUTPUT;
		}
		av_packet_rescale_ts(w->pkt, w->enc->time_base, w->st->time_base);
		w->pkt->stream_index = w->st->index;
		r = av_interleaved_write_frame(w->fmt, w->pkt);
		av_packet_unref(w->pkt);
		if (r < 0) {
			av_err(err, err_size, "cannot write to the clip", r);
			return TL_ERR_OUTPUT;
		}
	}
}

int clip_writer_frame(clip_writer *w, const uint8_t *rgb, char *err, size_t err_size)
{
	int r = av_frame_make_writable(w->frame);
	if (r < 0) {
		av_err(err, err_size, "frame buffer", r);
		return TL_ERR_OUTPUT;
	}
	/* GBRP planes: data[0] = G, data[1] = B, data[2] = R. */
	for (int y = 0; y < w->frame->height; y++) {
		uint8_t *g = w->frame->data[0] + (size_t)y * w->frame->linesize[0];
		uint8_t *b = w->frame->data[1] + (size_t)y * w->frame->linesize[1];
		uint8_t *rr = w->frame->data[2] + (size_t)y * w->frame->linesize[2];
		const uint8_t *src = rgb + (size_t)y * w->frame->width * 3;
		for (int x = 0; x < w->frame->width; x++) {
			rr[x] = src[x * 3];
			g[x] = src[x * 3 + 1];
			b[x] = src[x * 3 + 2];
		}
	}
	w->frame->pts = w->next_pts++;
	if ((r = avcodec_send_frame(w->enc, w->frame)) < 0) {
		av_err(err, err_size, "VP9 encoding failed", r);
		return TL_ERR_OUTPUT;
	}
	return drain(w, err, err_size);
}

int clip_writer_finish(clip_writer *w, char *err, size_t err_size)
{
	int r = avcodec_send_frame(w->enc, NULL);
	if (r < 0 && r != AVERROR_EOF) {
		av_err(err, err_size, "VP9 flush failed", r);
		return TL_ERR_OUTPUT;
	}
	if (drain(w, err, err_size))
		return TL_ERR_OUTPUT;
	if ((r = av_write_trailer(w->fmt)) < 0) {
		av_err(err, err_size, "cannot finish the WebM file", r);
		return TL_ERR_OUTPUT;
	}
	w->header_written = 0;
	if ((r = avio_closep(&w->fmt->pb)) < 0) {
		av_err(err, err_size, "cannot finish the WebM file", r);
		return TL_ERR_OUTPUT;
	}
	return tl_atomic_commit(&w->file, err, err_size);
}

void clip_writer_destroy(clip_writer **pw)
{
	if (!pw || !*pw)
		return;
	clip_writer *w = *pw;
	if (w->fmt && w->fmt->pb)
		avio_closep(&w->fmt->pb);
	tl_atomic_abort(&w->file);
	av_frame_free(&w->frame);
	av_packet_free(&w->pkt);
	avcodec_free_context(&w->enc);
	avformat_free_context(w->fmt);
	free(w);
	*pw = NULL;
}

int clip_decode(const char *path, clip_frame_fn frame, void *user, double *fps, char *err, size_t err_size)
{
	AVFormatContext *fmt = NULL;
	AVCodecContext *dec = NULL;
	AVPacket *pkt = av_packet_alloc();
	AVFrame *fr = av_frame_alloc();
	uint8_t *rgb = NULL;
	int rc = TL_ERR_INPUT, r;
	uint32_t index = 0;
	if (!pkt || !fr) {
		snprintf(err, err_size, "out of memory");
		goto done;
	}
	if ((r = avformat_open_input(&fmt, path, NULL, NULL)) < 0 || (r = avformat_find_stream_info(fmt, NULL)) < 0) {
		av_err(err, err_size, path, r);
		goto done;
	}
	int si = av_find_best_stream(fmt, AVMEDIA_TYPE_VIDEO, -1, -1, NULL, 0);
	if (si < 0) {
		snprintf(err, err_size, "%s: no video stream", path);
		goto done;
	}
	const AVCodec *codec = avcodec_find_decoder(fmt->streams[si]->codecpar->codec_id);
	dec = codec ? avcodec_alloc_context3(codec) : NULL;
	if (!dec || avcodec_parameters_to_context(dec, fmt->streams[si]->codecpar) < 0 || avcodec_open2(dec, codec, NULL) < 0) {
		snprintf(err, err_size, "%s: cannot open a decoder", path);
		goto done;
	}
	if (fps)
		*fps = av_q2d(fmt->streams[si]->avg_frame_rate);
	int eof = 0, stop = 0;
	while (!stop) {
		if (!eof) {
			r = av_read_frame(fmt, pkt);
			if (r == AVERROR_EOF) {
				eof = 1;
				avcodec_send_packet(dec, NULL);
			} else if (r < 0) {
				av_err(err, err_size, path, r);
				goto done;
			} else {
				if (pkt->stream_index == si && (r = avcodec_send_packet(dec, pkt)) < 0) {
					av_packet_unref(pkt);
					av_err(err, err_size, path, r);
					goto done;
				}
				av_packet_unref(pkt);
			}
		}
		for (;;) {
			r = avcodec_receive_frame(dec, fr);
			if (r == AVERROR(EAGAIN))
				break;
			if (r == AVERROR_EOF) {
				stop = 1;
				break;
			}
			if (r < 0) {
				av_err(err, err_size, path, r);
				goto done;
			}
			if (fr->format != AV_PIX_FMT_GBRP) {
				snprintf(err, err_size, "%s: frames are not 8-bit RGB (gbrp): not a taslab clip", path);
				goto done;
			}
			uint8_t *nr = realloc(rgb, (size_t)fr->width * fr->height * 3);
			if (!nr) {
				snprintf(err, err_size, "out of memory");
				goto done;
			}
			rgb = nr;
			for (int y = 0; y < fr->height; y++)
				for (int x = 0; x < fr->width; x++) {
					uint8_t *o = rgb + ((size_t)y * fr->width + x) * 3;
					o[0] = fr->data[2][(size_t)y * fr->linesize[2] + x];
					o[1] = fr->data[0][(size_t)y * fr->linesize[0] + x];
					o[2] = fr->data[1][(size_t)y * fr->linesize[1] + x];
				}
			if (frame(user, index++, (uint32_t)fr->width, (uint32_t)fr->height, rgb)) {
				stop = 1;
				break;
			}
		}
	}
	rc = 0;
done:
	free(rgb);
	av_frame_free(&fr);
	av_packet_free(&pkt);
	avcodec_free_context(&dec);
	avformat_close_input(&fmt);
	return rc;
}

int clip_encode_run(const char *run_dir, const char *out, uint32_t *frames_written, char *err, size_t err_size)
{
	return clip_encode_run_view(run_dir, NULL, out, frames_written, err, err_size);
}

int clip_encode_run_view(const char *run_dir, const char *view, const char *out, uint32_t *frames_written, char *err,
			 size_t err_size)
{
	char path[TL_PATH_MAX];
	clip_writer *w = NULL;
	uint8_t *rgb = NULL;
	run_manifest m;
	*frames_written = 0;
	int rc = run_manifest_read(run_dir, &m, err, err_size);
	if (rc || (rc = run_check_frames(run_dir, &m, "png", err, err_size)))
		return rc;
	/* stereo: the side-by-side frames (2W x H) unless one eye is asked for */
	const char *sub = "frames";
	if (view && m.views < 2 && strcmp(view, "sbs"))
		return tl_error(err, err_size, TL_ERR_ARG, "%s: a mono run has no eye '%s' (--eye is for stereo runs)", run_dir, view);
	if (m.views > 1)
		sub = !view || !strcmp(view, "sbs") ? "sbs" : !strcmp(view, "L") ? "frames/L" : !strcmp(view, "R") ? "frames/R" : NULL;
	if (!sub)
		return tl_error(err, err_size, TL_ERR_ARG, "--eye %s: one of L, R, sbs", view);
	if (m.views < 2)
		sub = "frames";
	uint32_t want_w = !strcmp(sub, "sbs") ? 2 * m.width : m.width;
	for (uint32_t f = m.first_frame; f <= m.last_frame; f++) {
		uint32_t fw, fh;
		snprintf(path, sizeof path, "%s/%s/%06u.png", run_dir, sub, f);
		free(rgb);
		rgb = NULL;
		if ((rc = imageio_read_rgb8_as(path, IMAGEIO_FORMAT_PNG, &fw, &fh, &rgb, err, err_size)))
			goto done;
		if (fw != want_w || fh != m.height) {
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: size %ux%u differs from the run's %ux%u; render the run again",
				      path, fw, fh, want_w, m.height);
			goto done;
		}
		if (!w && (rc = clip_writer_create(out, fw, fh, m.fps, &w, err, err_size)))
			goto done;
		if ((rc = clip_writer_frame(w, rgb, err, err_size)))
			goto done;
	}
	if ((rc = clip_writer_finish(w, err, err_size)))
		goto done;
	*frames_written = m.last_frame - m.first_frame + 1;
done:
	clip_writer_destroy(&w);
	free(rgb);
	return rc;
}
