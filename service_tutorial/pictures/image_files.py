"""
Image files written with Pillow: PNG stills and looping GIF animations.

These functions check their input and name what is wrong with it, and give a GIF one palette
for the whole clip, chosen from the pixels of every frame, so colours do not flicker from one
frame to the next; a clip of at most 256 colours keeps every colour exactly. Pillow stores
after the first frame only the rectangle that changed, and folds a frame identical to the one
before into that one's display time.
"""

import numpy as np
from PIL import Image

PNG_CHANNELS = (1, 2, 3, 4)  # grey, grey and alpha, RGB, RGBA
GIF_MAX_FPS = 50.0  # GIF delays are in 1/100 s, and viewers slow down delays under 2/100 s
GIF_COLOURS = 256
PALETTE_SAMPLE = 60000  # pixels of the clip the palette is chosen from


def write_png(path, image):
    """Write a uint8 image of shape (H, W), (H, W, 1), (H, W, 3) or (H, W, 4) as a PNG file."""
    pixels = np.asarray(image)
    if pixels.ndim == 3 and pixels.shape[2] == 1:
        pixels = pixels[:, :, 0]
    if pixels.dtype != np.uint8 or pixels.ndim not in (2, 3) or pixels.size == 0 or (
            pixels.ndim == 3 and pixels.shape[2] not in PNG_CHANNELS):
        raise ValueError(f'write_png needs a non-empty uint8 image with 1, 2, 3 or 4 channels, '
                         f'got {pixels.dtype} of shape {np.shape(image)}')
    Image.fromarray(np.ascontiguousarray(pixels)).save(path, format='PNG')
    return path


def write_animation(path, frames, fps=10.0):
    """Write RGB frames of one size, shown at fps frames per second, as a looping GIF."""
    frames = [np.asarray(frame) for frame in frames]
    if not frames:
        raise ValueError('write_animation needs at least one frame')
    shape = frames[0].shape
    for frame in frames:
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3 \
                or frame.shape != shape:
            raise ValueError(f'every frame must be uint8 RGB of shape {shape}, '
                             f'got {frame.dtype} of shape {frame.shape}')
    height, width = shape[:2]
    if not (0 < height <= 0xFFFF and 0 < width <= 0xFFFF):
        raise ValueError(f'a GIF is at most 65535 pixels wide and high, got {width}x{height}')
    if not 0.0 < fps <= GIF_MAX_FPS:
        raise ValueError(f'fps must be above 0 and at most {GIF_MAX_FPS:g}, got {fps}')

    images = palette_images(frames)
    # Display times in whole 1/100 s that add up to the clip's length at fps.
    ticks = [round(i * 100.0 / fps) for i in range(len(frames) + 1)]
    durations = [10 * (end - start) for start, end in zip(ticks, ticks[1:])]
    images[0].save(path, format='GIF', save_all=True, append_images=images[1:],
                   duration=durations, loop=0)
    return path


def palette_images(frames):
    """Map every frame onto one palette chosen for the whole clip; return Pillow 'P' images."""
    count = sum(frame.shape[0] * frame.shape[1] for frame in frames)
    stride = max(1, count // PALETTE_SAMPLE)
    sample = np.concatenate([frame.reshape(-1, 3)[::stride] for frame in frames])
    colours = np.unique(_packed(sample))
    if len(colours) <= GIF_COLOURS:
        # Few colours (a cartoon, a plot): each one kept exactly, if the sample saw them all.
        indices = [np.searchsorted(colours, _packed(frame)) for frame in frames]
        if all(np.array_equal(colours[np.minimum(index, len(colours) - 1)], _packed(frame))
               for index, frame in zip(indices, frames)):
            rgb = np.stack([colours >> 16, (colours >> 8) & 0xFF, colours & 0xFF], axis=1)
            images = [Image.fromarray(index.astype(np.uint8)) for index in indices]
            for image in images:
                image.putpalette(rgb.astype(np.uint8).reshape(-1).tolist())
            return images
    palette = Image.fromarray(np.ascontiguousarray(sample).reshape(-1, 1, 3)).quantize(
        GIF_COLOURS, method=Image.Quantize.MEDIANCUT)
    return [Image.fromarray(np.ascontiguousarray(frame)).quantize(
        palette=palette, dither=Image.Dither.NONE) for frame in frames]


def _packed(pixels):
    """Pack the RGB of (..., 3) uint8 pixels into one integer each."""
    pixels = pixels.astype(np.uint32)
    return (pixels[..., 0] << 16) | (pixels[..., 1] << 8) | pixels[..., 2]
