/* header_check.c / header_check.cpp — every public header compiles on its own as C11 and as C++
 * (checked at build time: this object library fails the build otherwise). */
#include "taslab/anim.h"
#include "taslab/imageio.h"
#include "taslab/render.h"
#include "taslab/run.h"
#include "taslab/scene.h"
#include "taslab/tl_math.h"
#include "taslab/vkdev.h"
#include "taslab/version.h"

int taslab_header_check(void);
int taslab_header_check(void) { return 0; }
