"""
Image files written with the standard library and numpy only: PNG stills and GIF animations.

PNG rows use the 'Up' filter, which suits rendered scenes (smooth from one row to the next),
and zlib. The GIF has one 255-colour palette for all frames, chosen by median cut over the
whole clip, and stores after the first frame only the rectangle that changed, with unchanged
pixels transparent; a camera that does not move makes small files that way.
"""

import struct
import zlib

import numpy as np

PNG_SIGNATURE = b'\x89PNG\r\n\x1a\n'
PNG_COLOUR_TYPES = {1: 0, 2: 4, 3: 2, 4: 6}  # channels -> grey, grey+alpha, RGB, RGBA

GIF_TRANSPARENT = 255  # palette index kept for 'unchanged since the previous frame'
GIF_MAX_FPS = 50.0  # GIF delays are in 1/100 s, and viewers slow down delays under 2/100 s
LZW_MIN_CODE_SIZE = 8
LZW_MAX_CODE = 4095


def write_png(path, image):
    """Write a uint8 image of shape (H, W), (H, W, 1), (H, W, 3) or (H, W, 4) as a PNG file."""
    pixels = np.asarray(image)
    if pixels.ndim == 2:
        pixels = pixels[:, :, np.newaxis]
    if pixels.dtype != np.uint8 or pixels.ndim != 3 or pixels.shape[2] not in PNG_COLOUR_TYPES \
            or pixels.shape[0] == 0 or pixels.shape[1] == 0:
        raise ValueError(f'write_png needs a non-empty uint8 image with 1, 2, 3 or 4 channels, '
                         f'got {pixels.dtype} of shape {np.shape(image)}')
    height, width, channels = pixels.shape
    rows = pixels.reshape(height, width * channels)
    up = rows.copy()
    up[1:] -= rows[:-1]  # uint8 arithmetic wraps modulo 256, as the filter wants
    filtered = np.empty((height, 1 + width * channels), dtype=np.uint8)
    filtered[:, 0] = 2  # filter type 'Up' on every row
    filtered[:, 1:] = up
    header = struct.pack('>IIBBBBB', width, height, 8, PNG_COLOUR_TYPES[channels], 0, 0, 0)
    with open(path, 'wb') as png_file:
        png_file.write(PNG_SIGNATURE)
        png_file.write(_png_chunk(b'IHDR', header))
        png_file.write(_png_chunk(b'IDAT', zlib.compress(filtered.tobytes(), 6)))
        png_file.write(_png_chunk(b'IEND', b''))
    return path


def _png_chunk(kind, payload):
    """Frame a PNG chunk: length, type, payload and the CRC of type and payload."""
    crc = zlib.crc32(kind + payload)
    return struct.pack('>I', len(payload)) + kind + payload + struct.pack('>I', crc)


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

    palette = median_cut_palette(_sample_pixels(frames), GIF_TRANSPARENT)
    nearest = _nearest_colour_table(palette)
    gif_palette = np.zeros((256, 3), dtype=np.uint8)
    gif_palette[:len(palette)] = palette

    # Display times in 1/100 s; identical frames lengthen the one before them.
    ticks = [round(i * 100.0 / fps) for i in range(len(frames) + 1)]
    pieces = []  # (start tick, left, top, indices, transparent)
    previous = None
    for number, frame in enumerate(frames):
        indices = nearest[_colour_cell(frame)]
        if previous is None:
            pieces.append((ticks[number], 0, 0, indices, False))
        else:
            changed = indices != previous
            if changed.any():
                rows = np.flatnonzero(changed.any(axis=1))
                cols = np.flatnonzero(changed.any(axis=0))
                box = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
                patch = np.where(changed[box], indices[box], GIF_TRANSPARENT).astype(np.uint8)
                pieces.append((ticks[number], int(cols[0]), int(rows[0]), patch, True))
        previous = indices

    with open(path, 'wb') as gif_file:
        gif_file.write(b'GIF89a')
        # Logical screen: a global colour table of 256 entries (8 bits per primary).
        gif_file.write(struct.pack('<HHBBB', width, height, 0xF7, 0, 0))
        gif_file.write(gif_palette.tobytes())
        # Loop forever (the NETSCAPE2.0 application extension).
        gif_file.write(b'\x21\xff\x0bNETSCAPE2.0\x03\x01' + struct.pack('<H', 0) + b'\x00')
        for number, (start, left, top, indices, transparent) in enumerate(pieces):
            end = pieces[number + 1][0] if number + 1 < len(pieces) else ticks[-1]
            # Graphic control: leave the frame in place for the next one to draw over.
            flags = (1 << 2) | int(transparent)
            gif_file.write(struct.pack('<BBBBHBB', 0x21, 0xF9, 4, flags, end - start,
                                       GIF_TRANSPARENT, 0))
            patch_height, patch_width = indices.shape
            gif_file.write(struct.pack('<BHHHHB', 0x2C, left, top, patch_width, patch_height, 0))
            gif_file.write(bytes([LZW_MIN_CODE_SIZE]))
            code = lzw_encode(indices.tobytes())
            for offset in range(0, len(code), 255):
                block = code[offset:offset + 255]
                gif_file.write(bytes([len(block)]) + block)
            gif_file.write(b'\x00')
        gif_file.write(b'\x3b')
    return path


def _sample_pixels(frames, count=60000):
    """Take up to `count` pixels spread evenly over all frames, as an (N, 3) array."""
    pixels = np.concatenate([frame.reshape(-1, 3) for frame in frames])
    stride = max(1, len(pixels) // count)
    return pixels[::stride]


def median_cut_palette(pixels, colours):
    """Pick up to `colours` colours for (N, 3) uint8 pixels by splitting the widest box."""
    boxes = [np.asarray(pixels, dtype=np.uint8).reshape(-1, 3)]
    while len(boxes) < colours:
        spans = [np.ptp(box, axis=0) for box in boxes]
        widest = max(range(len(boxes)), key=lambda i: spans[i].max())
        if spans[widest].max() == 0:
            break  # every box holds one colour
        box = boxes.pop(widest)
        axis = int(np.argmax(spans[widest]))
        box = box[np.argsort(box[:, axis], kind='stable')]
        # Split at the median, moved so that one colour value never sits in both halves.
        middle = len(box) // 2
        values = box[:, axis]
        middle = int(np.searchsorted(values, values[middle]))
        if middle == 0:
            middle = int(np.searchsorted(values, values[0], side='right'))
        boxes += [box[:middle], box[middle:]]
    return np.array([box.mean(axis=0) for box in boxes]).round().astype(np.uint8)


def _colour_cell(pixels):
    """Find each pixel's cell in a 32x32x32 grid of colours (5 bits per primary)."""
    cells = pixels.astype(np.int32) >> 3
    return (cells[..., 0] << 10) | (cells[..., 1] << 5) | cells[..., 2]


def _nearest_colour_table(palette):
    """Map every cell of the 32x32x32 colour grid to its nearest palette colour."""
    levels = np.arange(32) * 8 + 4
    grid = np.stack(np.meshgrid(levels, levels, levels, indexing='ij'), axis=-1).reshape(-1, 3)
    colours = palette.astype(np.int32)
    table = np.empty(len(grid), dtype=np.uint8)
    for start in range(0, len(grid), 4096):
        cells = grid[start:start + 4096, np.newaxis, :]
        table[start:start + 4096] = ((cells - colours) ** 2).sum(axis=2).argmin(axis=1)
    return table


def lzw_encode(indices):
    """Compress a byte string of 8-bit palette indices with GIF's variable-width LZW."""
    clear = 1 << LZW_MIN_CODE_SIZE
    end = clear + 1
    out = bytearray()
    bits = 0  # pending bits, least significant first
    pending = 0

    def emit(code, width):
        nonlocal bits, pending
        bits |= code << pending
        pending += width
        while pending >= 8:
            out.append(bits & 0xFF)
            bits >>= 8
            pending -= 8

    # Each table entry is a known string plus one more index, keyed by (code << 8) | index.
    table = {}
    next_code = end + 1
    width = LZW_MIN_CODE_SIZE + 1
    emit(clear, width)
    prefix = None
    for index in indices:
        if prefix is None:
            prefix = index
            continue
        key = (prefix << 8) | index
        code = table.get(key)
        if code is not None:
            prefix = code
            continue
        emit(prefix, width)
        table[key] = next_code
        next_code += 1
        if next_code > (1 << width) and width < 12:
            width += 1
        if next_code > LZW_MAX_CODE:
            # The table is full: start afresh, as a decoder that sees the clear code will.
            emit(clear, width)
            table.clear()
            next_code = end + 1
            width = LZW_MIN_CODE_SIZE + 1
        prefix = index
    if prefix is not None:
        emit(prefix, width)
        # A decoder adds one more entry on reading that last code, and widens its codes when
        # the table reaches the next power of two; the end code follows at that width.
        if next_code == (1 << width) and width < 12:
            width += 1
    emit(end, width)
    if pending:
        out.append(bits & 0xFF)
    return bytes(out)
