"""sensor_pictures draws tinybot's scan on the yard seen from above and saves a camera frame."""

import numpy as np
from PIL import Image
from service_tutorial.pictures.sensor_pictures import main, SCAN_COLOUR


def test_sensor_pictures_writes_the_scan_from_above_and_a_camera_frame(tmp_path, capsys):
    assert main(['--output', str(tmp_path), '--size', '200']) == 0
    printed = capsys.readouterr().out
    # The yard's walls close it all round: every one of the 360 beams returns.
    assert '360 laser returns drawn' in printed
    with Image.open(tmp_path / 'sensors_scan_from_above.png') as picture:
        top = np.asarray(picture.convert('RGB'))
    assert top.shape == (200, 200, 3)
    dots = np.all(top == SCAN_COLOUR, axis=2)
    assert dots.sum() > 360, 'the scan is not drawn'
    # The returns lie around the robot, at the middle of the picture, on every side.
    rows, columns = np.nonzero(dots)
    assert rows.min() < 40 and rows.max() > 160 and columns.min() < 40 and columns.max() > 160
    with Image.open(tmp_path / 'sensors_tinybot_camera.png') as frame:
        assert frame.size == (320, 240)
        pixels = np.asarray(frame.convert('RGB')).astype(int)
    # Turned toward the red crate, tinybot sees red in the middle of its camera's view.
    red = (pixels[:, :, 0] > 2 * pixels[:, :, 1]) & (pixels[:, :, 0] > 2 * pixels[:, :, 2])
    assert red[80:160, 100:220].mean() > 0.1
