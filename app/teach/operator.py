"""A careful operator at the teach page: headless Chromium (Debian's, through Selenium) typing the
scripted teacher's poses into the page's own fields and pressing its buttons, one step at a time.

The browser test and `scripts/page_demos.py` use it. It reads what an operator sees (the status
line, whose steps are numbered) and, to know where the teacher would grasp and place, the object
the session put down (the teacher needs the procedural object's landmarks).
"""
from __future__ import annotations

import shutil
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from app.tasks.task import teacher_grasp, teacher_place
from app.teach.page import TeachPage, ur_text
from hardware.se3 import make_pose, rotvec_to_matrix

CHROMIUM = ("/usr/bin/chromium", "/usr/bin/chromium-browser")
CHROMEDRIVER = ("/usr/bin/chromedriver", "/usr/lib/chromium/chromedriver")
HALF_TURN = make_pose(rotvec_to_matrix([0.0, 0.0, np.pi]))  # the two-finger gripper's symmetry


def find(candidates: tuple[str, ...], what: str) -> str:
    """The first executable there is, or a one-line error naming the Debian package."""
    for path in candidates:
        if Path(path).is_file() or shutil.which(path):
            return path
    raise FileNotFoundError(f"no {what} ({' or '.join(candidates)}): install Debian's chromium and "
                            f"chromium-driver (scripts/install.sh --test)")


def chromium(width: int = 1400, height: int = 900):
    """A headless Chromium under Selenium, rendering WebGL in software (SwiftShader)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    options.binary_location = find(CHROMIUM, "Chromium")
    for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", f"--window-size={width},{height}",
                 "--enable-unsafe-swiftshader", "--disable-gpu-sandbox"):
        options.add_argument(flag)
    return webdriver.Chrome(service=Service(find(CHROMEDRIVER, "chromedriver")), options=options)


@dataclass
class Operator:
    """Drives one page in one browser."""

    page: TeachPage
    driver: object
    timeout: float = 120.0

    def open(self) -> None:
        """Load the page and wait for its controls."""
        self.driver.get(self.page.url)
        self._button("New object", wait=60.0)
        for close in self.driver.find_elements("xpath", "//div[contains(., 'Software WebGL')]/button"):
            close.click()  # the notice that WebGL runs in software (headless) hides part of the scene

    # what the operator sees and does -------------------------------------------------------------------
    def status(self) -> str:
        """The numbered status line, '(7) held: ...' ('' before the first step)."""
        texts = self.driver.execute_script(  # read in one go: React replaces the elements as it re-renders
            "return Array.from(document.querySelectorAll('p')).map(p => p.innerText.trim())")
        return next((t for t in texts if t.startswith("(") and t[1:].split(")", 1)[0].isdigit()), "")

    def press(self, label: str) -> str:
        """Press a button and wait for the page's answer; the answer (without its number)."""
        from selenium.common.exceptions import StaleElementReferenceException

        before = self.page.answered
        for _ in range(5):
            try:
                self._button(label).click()
                break
            except StaleElementReferenceException:  # re-rendered between finding and clicking
                time.sleep(0.2)
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            line = self.status()
            if line.startswith(f"({before + 1})"):
                return line.split(")", 1)[1].strip()
            time.sleep(0.1)
        raise TimeoutError(f"the page did not answer {label!r} within {self.timeout:.0f} s (status: {self.status()!r})")

    def type(self, label: str, text: str) -> None:
        """Type into the field labelled `label` (replacing what is there) and wait until the page has it."""
        from selenium.webdriver.common.keys import Keys

        from selenium.common.exceptions import StaleElementReferenceException

        for _ in range(5):
            try:
                field = self.driver.find_element("xpath", f"//label[normalize-space()='{label}']/following::input[1]")
                field.send_keys(Keys.CONTROL, "a")
                field.send_keys(Keys.BACKSPACE)
                field.send_keys(text)
                break
            except StaleElementReferenceException:
                time.sleep(0.2)
        handle = {"TCP pose": self.page.tcp_text, "Object pose": self.page.obj_text,
                  "Instance": self.page.instance, "Put at": self.page.placement}[label]
        deadline = time.monotonic() + 10.0
        while handle.value != text and time.monotonic() < deadline:  # the field's value travels over the websocket
            time.sleep(0.05)

    def screenshot(self, path: Path) -> Path:
        self.driver.save_screenshot(str(path))
        return path

    def _button(self, label: str, wait: float = 10.0):
        deadline = time.monotonic() + wait
        while True:
            found = self.driver.find_elements("xpath", f"//button[normalize-space()='{label}']")
            if found and found[0].is_enabled():
                return found[0]
            if time.monotonic() > deadline:
                raise TimeoutError(f"no button {label!r} on the page")
            time.sleep(0.2)

    # one demo with the teacher's poses --------------------------------------------------------------
    def teach_one(self, instance: int | None = None, save: bool = True, at: str = "") -> list[str]:
        """Put an object down (at `at`, 'x y yaw', if given), grasp, carry and place it where the
        scripted teacher would, save; the page's answers in order (a 'Not done' ends the demo)."""
        session = self.page.session
        answers = []
        self.type("Instance", "" if instance is None else str(instance))
        self.type("Put at", at)
        answers.append(self.press("New object"))
        obj, T_obj = session.current.obj, session.current.T_base_obj
        for turn in (np.eye(4), HALF_TURN):  # a careful operator turns the wrist when the arm cannot reach
            self.type("TCP pose", ur_text(T_obj @ teacher_grasp(obj.mesh) @ turn))
            answers.append(self.press("Move TCP"))
            if not answers[-1].startswith("Not done"):
                break
        if answers[-1].startswith("Not done"):
            return answers
        answers.append(self.press("Close gripper"))
        if answers[-1].startswith("Not done"):
            return answers
        place = session.T_base_fixture @ teacher_place(session.task, obj.mesh, obj.scale)
        self.type("Object pose", ur_text(place))
        answers.append(self.press("Move object"))
        if answers[-1].startswith("Not done"):
            return answers
        answers.append(self.press("Release"))
        if save and not answers[-1].startswith("Not done"):
            answers.append(self.press("Save demo"))
        return answers
