// state_bits.glsl - the fields of state.z of the rrc/tarc cache (reproj.glsl; reproj/max_down_state.comp).
#ifndef TASLAB_REPROJ_STATE_BITS_GLSL
#define TASLAB_REPROJ_STATE_BITS_GLSL
// state.z
const uint AGE_MASK = 0xFFFFu;  // frames since the last shading at the current frame (saturates)
const uint NEW_BIT = 1u << 29;  // no valid cache entry this frame
const uint PHASE_BIT = 1u << 30; // shaded once since it became visible: shade again next frame (sec. 6 step 1)
const uint SHADE_BIT = 1u << 31; // rrc: shade this frame (miss, first frame, or tile refresh)
// bits 24..26: this frame's decision for `render --decisions` (frame_decision in taslab/frame.h)
const uint DEC_SHIFT = 24u;
const uint DEC_REUSED = 1u << DEC_SHIFT, DEC_NEW = 2u << DEC_SHIFT, DEC_SECOND = 3u << DEC_SHIFT;
const uint DEC_PREDICTED = 4u << DEC_SHIFT, DEC_SCHEDULED = 5u << DEC_SHIFT, DEC_LATE = 6u << DEC_SHIFT;
const uint DEC_MASK = 7u << DEC_SHIFT;
#endif
