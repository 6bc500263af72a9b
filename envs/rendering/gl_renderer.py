"""The camera's OpenGL renderer: the world's :class:`~stsf_gym.envs.rendering.scene.Scene` drawn
with moderngl.

A headless EGL context (Mesa's llvmpipe on a CPU, or a GPU's driver) is made once per process
and shared by every env in it. Each renderer uploads its scene's static triangles once (again
only when a fault shows or hides a board), the board textures in one mipmapped texture array,
so a frame is one view-projection matrix, one draw per material (plain surfaces, boards: on
llvmpipe a texture lookup in a shader costs on every pixel, even behind a branch) and one
read-back. Lighting is a fixed directional light plus ambient, so walls and floor differ in
shade as they do under PyBullet's renderers.

EGL cannot be used in a process forked after its parent made a context (Mesa deadlocks):
:func:`gl_inherited` tells, and :class:`~stsf_gym.envs.simulator.Simulator` then falls back.

In a worker process of a vector env (any process started by :mod:`multiprocessing`, as
Gymnasium's ``AsyncVectorEnv`` and stable-baselines3's ``SubprocVecEnv`` start theirs) llvmpipe
rasterises on :data:`WORKER_RASTER_THREADS` thread: its default of one thread per core has
every worker's threads contend for every core. A user's own ``LP_NUM_THREADS`` is kept.
"""

from __future__ import annotations

import multiprocessing
import os

import numpy as np

from stsf_gym.envs.rendering.scene import Scene

LIGHT_DIRECTION = (0.35, -0.25, 0.9)  # towards the light, world frame (mostly from above)
AMBIENT = 0.55
BACKGROUND = (0.9, 0.9, 0.92)
# Boards seen at a slant shrink more along one image axis than the other: anisotropic
# filtering averages the texture over each pixel's footprint (as a sensor's pixel integrates
# light), where plain mipmapping would blur it by the larger axis.
ANISOTROPY = 16.0  # no ceiling: what shows above the walls
WORKER_RASTER_THREADS = 1  # llvmpipe's threads in a vector env's worker process
ATTRIBUTES = ("3f 3f 2f 3f 1f", "position", "normal", "uv", "colour", "layer")

VERTEX_SHADER = """
#version 330
uniform mat4 view_projection;
in vec3 position;
in vec3 normal;
in vec2 uv;
in vec3 colour;
in float layer;
out vec3 v_normal;
out vec3 v_uvw;
out vec3 v_colour;
void main() {
    gl_Position = view_projection * vec4(position, 1.0);
    v_normal = normal;
    v_uvw = vec3(uv, layer);
    v_colour = colour;
}
"""

# Walls, floor and clutter: a colour lit by a fixed directional light plus ambient.
PLAIN_SHADER = """
#version 330
uniform vec3 light;
uniform float ambient;
in vec3 v_normal;
in vec3 v_uvw;
in vec3 v_colour;
out vec4 colour;
void main() {
    float shade = ambient + (1.0 - ambient) * abs(dot(normalize(v_normal), light));
    colour = vec4(v_colour * shade, 1.0);
}
"""

# Boards: their pattern, evenly lit (as PyBullet's renderers draw textures), filtered.
BOARD_SHADER = """
#version 330
uniform sampler2DArray boards;
in vec3 v_normal;
in vec3 v_uvw;
in vec3 v_colour;
out vec4 colour;
void main() {
    colour = vec4(vec3(texture(boards, v_uvw).r), 1.0);
}
"""

_context = None
_context_pid: int | None = None


def gl_inherited() -> bool:
    """True in a process forked after its parent made an EGL context: it would deadlock."""
    return _context_pid is not None and _context_pid != os.getpid()


def gl_context():
    """The process's headless OpenGL 3.3 context (made on first use); raises if none can be."""
    global _context, _context_pid
    if gl_inherited():
        raise RuntimeError("an EGL context was made before this process was forked")
    if _context is None:
        import moderngl

        if multiprocessing.parent_process() is not None:  # a vector env's worker
            os.environ.setdefault("LP_NUM_THREADS", str(WORKER_RASTER_THREADS))

        _context = moderngl.create_standalone_context(backend="egl", require=330)
        _context_pid = os.getpid()
    return _context


class GLRenderer:
    """Draws one :class:`Scene` for given OpenGL view and projection matrices."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.ctx = gl_context()
        with self.ctx:  # current for this work only: PyBullet's EGL plugin may hold another
            self._build_programs()
        self._uploaded = -1
        self._geometry: list = []  # (vertex array, its buffer, vertex count) per material
        self._textures = None
        self._targets: dict[tuple[int, int], object] = {}
        self._read: dict[tuple[int, int], bytearray] = {}  # read-back buffer per image size

    def _build_programs(self) -> None:
        self.programs = [
            self.ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=fragment)
            for fragment in (PLAIN_SHADER, BOARD_SHADER)
        ]
        light = np.asarray(LIGHT_DIRECTION, float)
        self.programs[0]["light"].value = tuple(light / np.linalg.norm(light))
        self.programs[0]["ambient"].value = AMBIENT

    def _upload(self) -> None:
        self._release_geometry()
        for program, vertices in zip(self.programs, self.scene.triangles(), strict=True):
            buffer = self.ctx.buffer(vertices.tobytes() or bytes(4))
            vao = self.ctx.vertex_array(program, [(buffer, *ATTRIBUTES)], skip_errors=True)
            self._geometry.append((vao, buffer, len(vertices)))
        textures = self.scene.textures or [np.zeros((1, 1), np.uint8)]
        height, width = textures[0].shape
        layers = np.stack([np.flipud(t) for t in textures])  # GL rows run bottom-up
        self._textures = self.ctx.texture_array(
            (width, height, len(textures)), 1, np.ascontiguousarray(layers).tobytes()
        )
        self._textures.build_mipmaps()
        self._textures.anisotropy = ANISOTROPY
        self._uploaded = self.scene.version

    def _target(self, width: int, height: int):
        """The framebuffer (colour and depth) of an image size, made on first use."""
        if (width, height) not in self._targets:
            self._targets[(width, height)] = self.ctx.framebuffer(
                color_attachments=[self.ctx.renderbuffer((width, height), 3)],
                depth_attachment=self.ctx.depth_renderbuffer((width, height)),
            )
        return self._targets[(width, height)]

    def render(
        self, width: int, height: int, view: np.ndarray, projection: np.ndarray
    ) -> np.ndarray:
        """RGB uint8 image (height, width, 3), top row first, for row-major 4x4 matrices.

        One view-projection matrix per frame and one draw per material (plain, boards)."""
        with self.ctx:
            return self._render(width, height, view, projection)

    def _render(self, width: int, height: int, view: np.ndarray, projection: np.ndarray):
        if self._uploaded != self.scene.version:
            self._upload()
        target = self._target(width, height)
        target.use()
        self.ctx.enable(self.ctx.DEPTH_TEST)
        self.ctx.clear(*BACKGROUND, 1.0)
        # GLSL matrices are column-major: the transpose's bytes are the row-major matrix
        view_projection = (projection @ view).T.astype(np.float32).tobytes()
        self._textures.use(0)
        for program, (vao, _, count) in zip(self.programs, self._geometry, strict=True):
            program["view_projection"].write(view_projection)
            if count:
                vao.render(vertices=count)
        data = self._read.setdefault((width, height), bytearray(width * height * 3))
        target.read_into(data, components=3, alignment=1)
        return np.frombuffer(data, np.uint8).reshape(height, width, 3)[::-1].copy()

    def _release_geometry(self) -> None:
        for vao, buffer, _ in self._geometry:
            vao.release()
            buffer.release()
        self._geometry.clear()
        if self._textures is not None:
            self._textures.release()
            self._textures = None

    def release(self) -> None:
        """Free this renderer's GL objects (the process's context stays)."""
        with self.ctx:
            self._release_all()

    def _release_all(self) -> None:
        self._release_geometry()
        for framebuffer in self._targets.values():
            for attachment in (*framebuffer.color_attachments, framebuffer.depth_attachment):
                attachment.release()
            framebuffer.release()
        self._targets.clear()
        for program in self.programs:
            program.release()
