#version 460
// fullscreen.vert - one triangle covering the viewport (passes that work per pixel with fixed-function
// stencil writes, e.g. the reuse decision of rrc/tarc). No vertex buffers.
void main()
{
	vec2 p = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
	gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
