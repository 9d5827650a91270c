#!/usr/bin/python3
# ssim_reference.py — independent SSIM reference values for tests/test_metrics.c, from scikit-image
# (Debian: python3-skimage 0.19), with the settings of Wang et al. 2004 that taslab implements:
# Gaussian window sigma 1.5 (11x11), K1 0.01, K2 0.03, data range 255, population covariance, per channel.
# The test images are integer formulas shared with test_metrics.c (make_pair there).
# Regenerate (Debian's python3, not a pyenv one): /usr/bin/python3 tests/reference/ssim_reference.py > tests/reference/ssim_reference.json
import json
import numpy as np
from skimage.metrics import structural_similarity

def make_pair(kind, w, h):
    a = np.zeros((h, w, 3)); b = np.zeros((h, w, 3))
    for y in range(h):
        for x in range(w):
            for c in range(3):
                if kind == 0:
                    va = (x * 7 + y * 13 + c * 29) % 256
                    vb = min(255, max(0, va + ((x * y + c) % 9) - 4))
                elif kind == 1:
                    va = (200 if ((x // 4) + (y // 4)) % 2 else 40) + c * 10
                    vb = (200 if (((x + 1) // 4) + (y // 4)) % 2 else 40) + c * 10
                else:
                    va = (x * x + 3 * y + 50 * c) % 256
                    vb = 255 - va if (x + y) % 7 == 0 else va
                a[y, x, c] = va; b[y, x, c] = vb
    return a, b

out = []
for kind, (w, h) in [(0, (32, 24)), (1, (17, 13)), (2, (40, 31))]:
    a, b = make_pair(kind, w, h)
    s = structural_similarity(a, b, channel_axis=2, gaussian_weights=True, sigma=1.5,
                              use_sample_covariance=False, data_range=255)
    out.append({"kind": kind, "width": w, "height": h, "ssim": float(s)})
print(json.dumps({"source": "scikit-image " + __import__("skimage").__version__ + " structural_similarity", "cases": out}, indent=1))
