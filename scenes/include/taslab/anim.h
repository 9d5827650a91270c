/* anim.h — time-driven animation: keyframe tracks and scripted motions.
 *
 * Everything here is a pure function of time t (seconds): no state is carried between
 * evaluations, so any frame of a clip, and any past frame (temporal forward rendering,
 * DESIGN section 4), can be evaluated directly (DESIGN section 2).
 *
 * Keyframe interpolation follows the glTF 2.0 specification, Appendix C:
 *  STEP        value of the last key at or before t;
 *  LINEAR      lerp (slerp for rotations);
 *  CUBICSPLINE Hermite spline with in/out tangents scaled by the key interval
 *              (values stored as in glTF: in-tangent, value, out-tangent per key).
 * Before the first key / after the last key the end values are held.
 *
 * Ownership: a track owns its `times` and `values` arrays (anim_track_finish frees them).
 */
#ifndef TASLAB_ANIM_H
#define TASLAB_ANIM_H

#include <stddef.h>

#include "taslab/tl_math.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum anim_interp {
	ANIM_INTERP_INVALID = 0,
	ANIM_INTERP_STEP,
	ANIM_INTERP_LINEAR,
	ANIM_INTERP_CUBICSPLINE,
	ANIM_INTERP_COUNT
} anim_interp;

typedef enum anim_path {
	ANIM_PATH_INVALID = 0,
	ANIM_PATH_TRANSLATION, /* 3 components */
	ANIM_PATH_ROTATION,    /* 4 components, quaternion xyzw */
	ANIM_PATH_SCALE,       /* 3 components */
	ANIM_PATH_COUNT
} anim_path;

typedef struct anim_track {
	anim_path path;
	anim_interp interp;
	size_t key_count;
	float *times;  /* key_count, strictly increasing */
	float *values; /* key_count * comps (x3 for CUBICSPLINE) */
} anim_track;

/* Number of float components of a path's values (3 or 4). */
int anim_path_components(anim_path path);
/* Parses "STEP" / "LINEAR" / "CUBICSPLINE" (case-sensitive, as in glTF); INVALID otherwise. */
anim_interp anim_interp_from_string(const char *s);
const char *anim_interp_name(anim_interp interp);

/* Checks key count, strictly increasing times, finite values and non-zero rotation keys; returns TL_OK, or
 * TL_ERR_INPUT with a one-line reason in `why`. */
int anim_track_validate(const anim_track *track, char *why, size_t why_size);
/* Samples the track at time t into out[0..components-1]. Rotations come back normalised. */
void anim_track_sample(const anim_track *track, float t, float out[4]);
/* Applies a sampled track to a TRS (replaces the channel). */
void anim_track_apply(const anim_track *track, float t, tlm_trs *trs);
void anim_track_finish(anim_track *track);

/* Scripted motions, composed on top of an object's base transform in the order listed.
 * Each is an analytic function of t. */
typedef enum anim_motion_kind {
	ANIM_MOTION_INVALID = 0,
	ANIM_MOTION_SPIN,  /* rotate about `axis` (through the object origin) at `rate` degrees/s */
	ANIM_MOTION_ORBIT, /* sets translation = center + radius*(u cos a + v sin a), a = phase + rate*t, u = +X (or +Z
	                     when the axis is near X) projected into the plane normal to the axis, v = axis x u:
	                     u rotated about the axis by a, counter-clockwise seen from +axis (as SPIN) */
	ANIM_MOTION_BOB,   /* translation += amplitude * sin(2*pi*frequency*t + phase) */
	ANIM_MOTION_TRACKS,/* keyframe tracks (translation / rotation / scale) */
	ANIM_MOTION_FALL,  /* ballistic fall from the current translation with bounces on a floor, closed form */
	ANIM_MOTION_COUNT
} anim_motion_kind;

typedef struct anim_motion {
	anim_motion_kind kind;
	tlm_vec3 axis;      /* SPIN, ORBIT: rotation axis (normalised at evaluation) */
	tlm_vec3 center;    /* ORBIT */
	tlm_vec3 amplitude; /* BOB */
	float rate_deg_s;   /* SPIN, ORBIT */
	float radius;       /* ORBIT */
	float frequency_hz; /* BOB */
	float phase_deg;    /* SPIN, ORBIT, BOB: value at t = 0 */
	float start_s;      /* motion is frozen at its t = start_s state before start_s */
	tlm_vec3 velocity;  /* FALL: initial velocity (m/s) */
	float gravity;      /* FALL: m/s^2, pulling along -Y */
	float floor_y;      /* FALL: height of the object origin when resting on the floor */
	float restitution;  /* FALL: bounce speed ratio 0..1 (also applied to horizontal speed at each bounce) */
	size_t track_count; /* TRACKS */
	anim_track *tracks; /* TRACKS: owned */
} anim_motion;

const char *anim_motion_kind_name(anim_motion_kind kind);
/* Applies one motion at time t to `trs` (in place). */
void anim_motion_apply(const anim_motion *motion, float t, tlm_trs *trs);
void anim_motion_finish(anim_motion *motion);

#ifdef __cplusplus
}
#endif
#endif
