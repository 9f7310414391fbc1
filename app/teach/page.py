"""The teach page (`nift teach --web`): the operator's controls beside the live cell, in a browser.

Built on viser (a headless Python server of a three.js scene with gizmos and controls): it draws
URDFs, point clouds and meshes and sends GUI events back to Python, which is all a teach pendant
needs. Every control calls one `TeachSession` step; its one-line answer goes to the status line.
A step that fails for the operator's reason (`ValueError`) says so there; anything else is logged
with its traceback and shown as one line too. Nothing the page does stops the server.
"""
from __future__ import annotations

import logging
import threading
from typing import Callable

import numpy as np
import viser

from app.failures import CellFailure
from app.objects import generate
from app.objects.library import load_object
from app.teach.gate import gated_server, new_token
from app.teach.session import Step, TeachSession
from app.teach.view import CellView, pose_of
from hardware.se3 import invert, pose_to_ur, ur_to_pose

log = logging.getLogger("nift.teach")
REDRAW_EVERY = 16  # physics steps between redraws while the cell moves (~15 per simulated second)


def parse_pose(text: str, what: str) -> np.ndarray:
    """(4, 4) from a UR pose 'x y z rx ry rz' (metres, rotation vector in radians), or a one-line error."""
    try:
        values = np.array([float(v) for v in text.replace(",", " ").replace("[", " ").replace("]", " ").split()])
    except ValueError:
        values = np.array([])
    if values.shape != (6,) or not np.isfinite(values).all():
        raise ValueError(f"{what}: give 6 numbers x y z rx ry rz (m, rad), got {text.strip()!r}")
    return ur_to_pose(values)


def ur_text(T: np.ndarray) -> str:
    return " ".join(f"{v:.4f}" for v in pose_to_ur(T))


class TeachPage:
    """The page's controls on a viser server, bound to a session."""

    def __init__(self, session: TeachSession, host: str = "127.0.0.1", port: int = 8080, token: str | None = None) -> None:
        self.session = session
        self.token = token or new_token()  # the page answers only its URL's token (app.teach.gate)
        self.server = gated_server(self.token, host=host, port=port, label="NIFT cell - teach", verbose=False)
        self.view = CellView(self.server, session)
        self._steps = 0
        self.answered = 0  # steps answered so far: the status line starts with the count ("(3) held: ...")
        self._build_gui()
        session.cell.world.on_step.append(self._on_step)
        self.view.update()

    @property
    def url(self) -> str:
        return f"http://{self.server.get_host()}:{self.server.get_port()}/?token={self.token}"

    def stop(self) -> None:
        self.session.cell.world.on_step.remove(self._on_step)
        self.server.stop()

    # controls ------------------------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui, t = self.server.gui, self.session.task
        gui.configure_theme(control_width="large", dark_mode=False)
        gui.add_markdown(f"**Teach: {t.name}** - grasp the {t.category}, place it on the {t.fixture}")
        self.status = gui.add_markdown("Put an object on the table to begin.")
        self.progress = gui.add_progress_bar(0.0, visible=False)
        with gui.add_folder("1. Object"):
            self.instance = gui.add_text("Instance", "", hint="which training instance (a number); blank: a random one")
            self.placement = gui.add_text("Put at", "", hint="x y yaw on the table (m, m, rad); blank: a random place")
            self._button("New object", lambda: self.session.new_object(instance=self._instance(),
                                                                         placement=self._placement()))
        with gui.add_folder("2. Freedrive"):
            self.tcp_text = gui.add_text("TCP pose", "", hint="x y z rx ry rz, base frame (m, rad); or drag the gizmo")
            self._button("Move TCP", lambda: self.session.guide(parse_pose(self.tcp_text.value, "TCP pose")))
        with gui.add_folder("3. Grasp"):
            self._button("Close gripper", lambda: self.session.close_gripper())
            self.held = gui.add_markdown("Held: no")
        with gui.add_folder("4. Place"):
            self.obj_text = gui.add_text("Object pose", "", hint="where to carry the held object (x y z rx ry rz)")
            self._button("Move object", self._move_object)
            self._button("Release", lambda: self.session.release())
        with gui.add_folder("5. Save"):
            self._button("Save demo", lambda: self.session.save_demo(self._progress), long=True)
            self.demos = gui.add_dropdown("Demos", ["(none)"])
            self._button("Show demo", self._show_demo)
            self._button("Delete demo", lambda: self.session.delete_demo(self.demos.value, self._progress), long=True)
        with gui.add_folder("6. Try it"):
            self._button("Imitate on an unseen object", self._try, long=True)
        self.gizmo_busy = threading.Lock()
        self.view.gizmo.on_update(self._dragged)
        self._refresh_fields()

    def _button(self, label: str, action: Callable[[], Step | None], long: bool = False) -> viser.GuiButtonHandle:
        button = self.server.gui.add_button(label)

        def clicked(_event) -> None:
            button.disabled = True
            try:
                self._run(label, action, long)
            finally:
                button.disabled = False

        button.on_click(clicked)
        return button

    def _run(self, label: str, action: Callable[[], Step | None], long: bool = False) -> None:
        """One step: its answer on the status line, the scene and fields redrawn; errors as one line."""
        if long:
            self._progress(0.0, f"{label}...")
        try:
            step = action()
            if step is not None:
                self._say(step.message if step.ok else f"Not done: {step.message}")
        except (ValueError, CellFailure) as exc:  # bad input, or what the cell could not do
            self._say(f"Not done: {exc}")
        except Exception as exc:  # noqa: BLE001 - a bug of ours: one line here, the traceback in the log
            log.exception("teach page: %s failed", label)
            self._say(f"Internal error in {label}: {type(exc).__name__}: {exc} (traceback in the server's log)")
        finally:
            self.progress.visible = False
            self.view.update()
            self._refresh_fields()

    def _say(self, line: str) -> None:
        self.answered += 1
        self.status.content = f"({self.answered}) {line}".replace("\n", " ")
        log.info(line)

    def _progress(self, fraction: float, text: str) -> None:
        self.progress.visible = True
        self.progress.value = 100.0 * fraction
        self.status.content = text

    def _refresh_fields(self) -> None:
        s = self.session
        self.tcp_text.value = ur_text(s.tcp())
        pose = s.object_pose()
        self.obj_text.value = "" if pose is None else ur_text(pose)
        held = s.current is not None and s.current.held
        self.held.content = "Held: yes" if held else "Held: no"
        names = s.demo_names()
        self.demos.options = names or ["(none)"]
        if self.demos.value not in self.demos.options:
            self.demos.value = self.demos.options[-1]

    def _instance(self) -> int | None:
        text = self.instance.value.strip()
        if not text:
            return None
        if not text.isdigit():
            raise ValueError(f"Instance: give a whole number or leave it blank, got {text!r}")
        return int(text)

    def _placement(self) -> tuple[float, float, float] | None:
        text = self.placement.value.replace(",", " ").split()
        if not text:
            return None
        try:
            x, y, yaw = (float(v) for v in text)
        except ValueError:
            raise ValueError(f"Put at: give x y yaw (m, m, rad) or leave it blank, got {' '.join(text)!r}") from None
        return x, y, yaw

    # actions with more than one call -----------------------------------------------------------------
    def _move_object(self) -> Step:
        s = self.session
        T_obj = parse_pose(self.obj_text.value, "Object pose")
        if s.current is None or not s.current.held:
            raise ValueError("nothing is held: close the gripper on the object first")
        return s.guide(T_obj @ invert(s.current.T_tcp_obj))

    def _show_demo(self) -> Step:
        demo = self.session.demo(self.demos.value)
        mesh = load_object(demo.object).mesh.copy() if demo.object else generate(demo.category, demo.seed)
        mesh.apply_scale(demo.scale)
        self.view.clear_ghosts()
        self.view.show_demo(demo, mesh)
        return Step(True, f"{demo.name}: {demo.category} {demo.object or demo.seed}, taught by {demo.taught}; "
                          f"grasp and place shown as ghosts")

    def _try(self) -> Step:
        self.view.clear_ghosts()
        step = self.session.try_imitation()
        if step.ok:
            self.view.show_prediction()
        return step

    def _dragged(self, _handle) -> None:
        """The gizmo moved: the arm follows, or the ghost turns red and the page says why."""
        if not self.gizmo_busy.acquire(blocking=False):
            return  # a drag event arrives while the last is being answered: the next one will catch up
        try:
            T = pose_of(np.asarray(self.view.gizmo.position), np.asarray(self.view.gizmo.wxyz))
            step = self.session.guide(T)
            if step.ok:
                self.view.update(move_gizmo=False)
                self._refresh_fields()
            else:
                self.view.mark(False, T)
                self._say(f"Cannot go there: {step.message}")
        except Exception as exc:  # noqa: BLE001 - never let a drag take the page down
            log.exception("teach page: drag failed")
            self._say(f"Internal error while dragging: {type(exc).__name__}: {exc}")
        finally:
            self.gizmo_busy.release()

    def _on_step(self) -> None:
        """Redraw every REDRAW_EVERY physics steps while the cell moves (a close, a lift, a release)."""
        self._steps += 1
        if self._steps % REDRAW_EVERY == 0:
            self.view.update()

