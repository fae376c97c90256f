#!/usr/bin/env python3
"""SSIM of image pairs by scikit-image, the figure renderer/compare's ssim metric is checked against.

Usage: ssim_values.py MODE REF NEW [REF NEW ...]   (MODE: luminance or each)
Prints one JSON list of mean SSIMs. Images are read as stored and scaled to [0, 1] (8-bit PNG),
as `farm compare` reads them; luminance is Rec. 709 (0.2126 R + 0.7152 G + 0.0722 B). The
window is Wang et al.'s: Gaussian, sigma 1.5, no sample-covariance correction, data range 1.
"""
import json
import sys

import numpy as np
from skimage.io import imread
from skimage.metrics import structural_similarity


def load(path):
    image = imread(path)
    scale = 65535.0 if image.dtype == np.uint16 else 255.0
    return image[..., :3].astype(np.float64) / scale


def main():
    mode, files = sys.argv[1], sys.argv[2:]
    values = []
    for ref_path, new_path in zip(files[0::2], files[1::2]):
        a, b = load(ref_path), load(new_path)
        options = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1.0)
        if mode == "luminance":
            weights = np.array([0.2126, 0.7152, 0.0722])
            values.append(structural_similarity(a @ weights, b @ weights, **options))
        else:
            values.append(structural_similarity(a, b, channel_axis=2, **options))
    print(json.dumps([float(v) for v in values]))


if __name__ == "__main__":
    main()
