"""
A real browser on the world's web page: headless Chromium driven by Selenium, and its pixels.

Debian's chromium and chromium-driver render WebGL without a GPU through SwiftShader. A test
asks for a Browser through browser_or_skip(), which skips with one line saying what is missing
when the browser or Selenium is not there (scripts/test installs the browser as root).
"""

import io
import shutil
import socket
import time

import numpy as np
from PIL import Image
import pytest

CHROMIUM_NAMES = ('chromium', 'chromium-browser', 'google-chrome')
CHROMIUM_ARGUMENTS = ('--headless=new', '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
                      '--no-sandbox', '--disable-dev-shm-usage', '--window-size=1280,800')
# Where the 3D view shows the world: left of the panel, below the software-WebGL notice.
VIEW_TOP = 170
VIEW_LEFT = 70
# Tinybot's blue body, (0.16, 0.38, 0.74) shaded: a pixel far bluer than it is red or green.
BLUE_OVER_RED = 70
BLUE_OVER_GREEN = 40


def free_port():
    """Return a TCP port on localhost that nothing listens on now."""
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        return probe.getsockname()[1]


def browser_or_skip():
    """Return a started Browser, or skip the test with one line saying what is missing."""
    chromium = next((shutil.which(name) for name in CHROMIUM_NAMES if shutil.which(name)), None)
    driver = shutil.which('chromedriver')
    if chromium is None or driver is None:
        pytest.skip('no chromium and chromium-driver: as root, scripts/test installs them '
                    '(apt install chromium chromium-driver)')
    try:
        import selenium  # noqa: F401
    except ImportError:
        pytest.skip('selenium is not installed: run scripts/setup')
    return Browser(chromium, driver)


class Browser:
    """One headless Chromium window."""

    def __init__(self, chromium, driver):
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
        options = webdriver.ChromeOptions()
        options.binary_location = chromium
        for argument in CHROMIUM_ARGUMENTS:
            options.add_argument(argument)
        self.driver = webdriver.Chrome(options=options, service=Service(driver))

    def load(self, address, *, timeout=30.0):
        """Load the page and wait until its panel is there."""
        self.driver.get(address)
        self.button('Spawn R2-D2', timeout=timeout)
        # viser's notice that WebGL runs in software (no GPU here) goes, as a person closes it.
        for close in self.driver.find_elements('css selector',
                                               '.mantine-Notification-closeButton'):
            close.click()

    def button(self, label, *, timeout=30.0):
        """Return the page's button with this label, once it is there."""
        return self._wait(lambda: self.driver.find_elements(
            'xpath', f"//button[normalize-space()='{label}']"), timeout, f'button {label!r}')[0]

    def click(self, label):
        """Click a button of the page as a person would."""
        self.button(label).click()

    def tick(self, label):
        """Tick or untick the checkbox with this label, as a click on its label does."""
        label_element = self._wait(lambda: self.driver.find_elements(
            'xpath', f"//label[normalize-space()='{label}']"), 30.0, f'checkbox {label!r}')[0]
        label_element.click()

    def choose(self, label, option, *, timeout=30.0):
        """Open the dropdown with this label and click one of its options."""
        label_element = self._wait(lambda: self.driver.find_elements(
            'xpath', f"//label[normalize-space()='{label}']"), timeout, f'dropdown {label!r}')[0]
        self.driver.find_element('id', label_element.get_attribute('for')).click()
        self._wait(lambda: self.driver.find_elements(
            'xpath', f"//*[@role='option' and normalize-space()='{option}']"), timeout,
            f'option {option!r} of {label!r}')[0].click()

    def panel_image(self, *, timeout=30.0):
        """Return the picture the panel shows (a robot camera's), as an RGB array."""
        image = self._wait(lambda: [element for element in self.driver.find_elements(
            'xpath', "//img[starts-with(@src, 'blob:')]") if element.size['height'] > 10],
            timeout, 'an image in the panel')[0]
        self.driver.execute_script('arguments[0].scrollIntoView(true);', image)
        return np.asarray(Image.open(io.BytesIO(image.screenshot_as_png)).convert('RGB'))

    def panel_images(self):
        """Return how many pictures the panel shows, counted in the page at one moment."""
        return self.driver.execute_script(
            "return Array.from(document.querySelectorAll('img[src^=\"blob:\"]'))"
            '.filter(image => image.getBoundingClientRect().height > 10).length;')

    def type_into(self, label, text):
        """Replace what the text field with this label holds, as typing would."""
        from selenium.webdriver.common.keys import Keys
        field = self._wait(lambda: self.driver.find_elements(
            'xpath', f"//label[normalize-space()='{label}']/following::input[1]"), 30.0,
            f'field {label!r}')[0]
        field.send_keys(Keys.CONTROL, 'a')
        field.send_keys(text, Keys.ENTER)

    def text(self):
        """Return the page's visible text."""
        return self.driver.find_element('tag name', 'body').text

    def wait_for_text(self, fragment, *, timeout=30.0):
        """Wait until the page shows a piece of text; return the page's text."""
        self._wait(lambda: fragment in self.text(), timeout, f'{fragment!r} on the page')
        return self.text()

    def wait_for_line(self, start, *, timeout=30.0):
        """Wait until a line of the page's text starts with start; return that line."""
        def line():
            return [text for text in self.text().splitlines() if text.startswith(start)]
        return self._wait(line, timeout, f'a line {start!r}... on the page')[0]

    def screenshot(self):
        """Return what the window shows, as an RGB array."""
        png = self.driver.get_screenshot_as_png()
        return np.asarray(Image.open(io.BytesIO(png)).convert('RGB'))

    def view(self, pixels):
        """Return the part of a screenshot where the 3D view shows the world."""
        panel_left = self.button('Spawn R2-D2').location['x'] - 20
        return pixels[VIEW_TOP:, VIEW_LEFT:panel_left].astype(int)

    def save(self, path):
        """Save a screenshot to path."""
        self.driver.save_screenshot(path)

    def close(self):
        """Close the window and end the browser (the page sees its client leave), once."""
        if self.driver is not None:
            self.driver.quit()
            self.driver = None

    @staticmethod
    def _wait(find, timeout, what):
        """Return what find() finds once it finds something; a replaced element is found anew."""
        from selenium.common.exceptions import StaleElementReferenceException
        deadline = time.monotonic() + timeout
        while True:
            try:
                found = find()
            except StaleElementReferenceException:
                found = None
            if found:
                return found
            assert time.monotonic() < deadline, f'no {what} within {timeout} s'
            time.sleep(0.05)


def blue_pixels(view):
    """Count the pixels of a view as blue as tinybot's body."""
    red, green, blue = view[..., 0], view[..., 1], view[..., 2]
    return int(np.count_nonzero((blue - red > BLUE_OVER_RED) & (blue - green > BLUE_OVER_GREEN)))


def red_pixels(view):
    """Count the pixels of a view as red as the page's laser points (nothing else is)."""
    red, green, blue = view[..., 0], view[..., 1], view[..., 2]
    return int(np.count_nonzero((red > 180) & (green < 80) & (blue < 80)))


def changed_pixels(before, after, *, threshold=40):
    """Count the pixels of two views of the same size that differ clearly."""
    return int(np.count_nonzero(np.abs(after - before).sum(axis=2) > threshold))
