//! Peer renderer on OpenGL ES 3.0 through EGL, headless: on a machine without a GPU this is
//! Mesa's llvmpipe, a multi-threaded JIT-compiled software rasterizer (its thread count follows
//! the CPU count, or the `LP_NUM_THREADS` environment variable).
//!
//! libEGL is loaded at run time (khronos-egl's `dynamic` feature), so the benchmark builds on
//! machines without EGL and this peer reports an error instead. The display comes from the
//! `EGL_MESA_platform_surfaceless` platform (no X11 or Wayland needed), the context is made
//! current without a surface (`EGL_KHR_surfaceless_context`, with a 1x1 pbuffer as fallback),
//! and the image is drawn into a framebuffer object of our own size.
//!
//! The scene's matrix produces clip-space depth `z / w` in `[0, 1]` (Vulkan/wgpu convention);
//! OpenGL ES clips `z / w` to `[-1, 1]`, so the vertex shader remaps `z` to `2 z - w`, which
//! gives the same window depth in `[0, 1]` (`glClipControl` is not part of OpenGL ES 3.0).
//!
//! A `GlPeer` holds raw EGL handles, so it is neither `Send` nor `Sync`: it stays on the thread
//! that created it, the thread its GL context is current on.

use std::ffi::c_void;

use glow::HasContext;
use khronos_egl as egl;

use super::peer_scene::PeerScene;

/// `EGL_PLATFORM_SURFACELESS_MESA` from `EGL_MESA_platform_surfaceless`: a display that needs
/// no window system.
const PLATFORM_SURFACELESS_MESA: egl::Enum = 0x31DD;

/// What to install when EGL or the Mesa drivers are missing (Debian and Ubuntu package names).
const PACKAGES_HINT: &str = "install libegl1 libegl-mesa0 libgl1-mesa-dri";

/// The clear colour, opaque black, as read back in RGBA8.
const CLEAR_RGBA8: [u8; 4] = [0, 0, 0, 255];

/// Attribute location of `a_position` in [`VERTEX_SHADER`].
const POSITION_LOCATION: u32 = 0;
/// Attribute location of `a_normal` in [`VERTEX_SHADER`].
const NORMAL_LOCATION: u32 = 1;
/// Bytes between consecutive positions or normals: three tightly packed `f32`.
const VEC3_STRIDE: i32 = std::mem::size_of::<[f32; 3]>() as i32;

/// Per-vertex (Gouraud) diffuse lighting and the `[0, 1]` to `[-1, 1]` clip depth remap.
const VERTEX_SHADER: &str = "#version 300 es
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;

uniform mat4 u_clip_from_world;
uniform vec3 u_color;
uniform vec3 u_light;

out vec3 v_color;

void main() {
    float intensity = 0.15 + 0.85 * max(dot(a_normal, u_light), 0.0);
    v_color = u_color * intensity;

    vec4 clip = u_clip_from_world * vec4(a_position, 1.0);
    // The matrix targets z/w in [0, 1]; OpenGL clips z/w to [-1, 1].
    clip.z = 2.0 * clip.z - clip.w;
    gl_Position = clip;
}
";

/// Writes the interpolated vertex colour, opaque.
const FRAGMENT_SHADER: &str = "#version 300 es
precision highp float;

in vec3 v_color;
out vec4 o_color;

void main() {
    o_color = vec4(v_color, 1.0);
}
";

/// EGL entry points loaded from libEGL at run time: EGL 1.4 at least, 1.5 used when present.
type Egl = egl::DynamicInstance<egl::EGL1_4>;

/// Renders the standard scene with OpenGL ES 3.0 into an offscreen framebuffer.
pub struct GlPeer {
    gl: glow::Context,
    program: glow::Program,
    clip_from_world_location: glow::UniformLocation,
    vertex_array: glow::VertexArray,
    /// Positions, normals and indices.
    buffers: [glow::Buffer; 3],
    framebuffer: glow::Framebuffer,
    /// RGBA8 colour and 24-bit depth.
    renderbuffers: [glow::Renderbuffer; 2],
    index_count: i32,
    width: i32,
    height: i32,
    /// `GL_RENDERER`, read once at creation.
    renderer: String,
    /// Read-back buffer for [`GlPeer::coverage`], `width * height` RGBA8 pixels.
    pixels: Vec<u8>,
    /// Declared last so that it is dropped last: `Drop for GlPeer` deletes the GL objects while
    /// the context is still alive and current.
    session: EglSession,
}

impl GlPeer {
    /// Creates a headless OpenGL ES 3.0 context, a `width` x `height` framebuffer, the shader
    /// program, and uploads `scene`'s mesh once (its colour and light become uniforms).
    ///
    /// Every failure (no libEGL, no surfaceless display, no ES 3 config, shader errors, an
    /// incomplete framebuffer, a GL error) is returned as a message rather than a panic, so
    /// that the benchmark can skip this peer.
    pub fn new(width: u32, height: u32, scene: &PeerScene) -> Result<Self, String> {
        let (width, height) = match (i32::try_from(width), i32::try_from(height)) {
            (Ok(w), Ok(h)) if w > 0 && h > 0 => (w, h),
            _ => return Err(format!("invalid GL peer image size {width}x{height}")),
        };
        let index_count = validate_scene(scene)?;

        let session = EglSession::new()?;
        // SAFETY: `EglSession::new` made the context current on this thread, which glow needs
        // to read GL_VERSION and the extensions; every pointer the loader hands back is the one
        // eglGetProcAddress returned for that name, or null when there is none.
        let gl = unsafe {
            glow::Context::from_loader_function(|name| {
                session.api.get_proc_address(name).map_or(std::ptr::null(), |function| function as *const c_void)
            })
        };
        // SAFETY: the context is current; GL_RENDERER is a valid `glGetString` name.
        let renderer = unsafe { gl.get_parameter_string(glow::RENDERER) };

        let program = compile_program(&gl)?;
        let clip_from_world_location = set_up_program(&gl, program, scene)?;
        let (vertex_array, buffers) = upload_mesh(&gl, scene)?;
        let (framebuffer, renderbuffers) = create_framebuffer(&gl, width, height)?;
        set_up_fixed_state(&gl, width, height);

        // SAFETY: the context is current.
        let error = unsafe { gl.get_error() };
        if error != glow::NO_ERROR {
            return Err(format!("GL error 0x{error:04X} while setting up the GL peer on {renderer}"));
        }

        let pixel_bytes = width as usize * height as usize * CLEAR_RGBA8.len();
        Ok(Self {
            gl,
            program,
            clip_from_world_location,
            vertex_array,
            buffers,
            framebuffer,
            renderbuffers,
            index_count,
            width,
            height,
            renderer,
            pixels: vec![0; pixel_bytes],
            session,
        })
    }

    /// Clears, draws the scene seen through `clip_from_world` (column-major, clip depth in
    /// `[0, 1]`, y up) with depth test "less" and back faces culled, then waits with `glFinish`
    /// so that the measured time covers the whole frame and not just command submission.
    pub fn render(&mut self, clip_from_world: [f32; 16]) {
        debug_assert_eq!(
            self.session.api.get_current_context(),
            Some(self.session.context),
            "the GL peer's context is not current on this thread"
        );
        let gl = &self.gl;
        // SAFETY: the context is current on this thread (a `GlPeer` cannot leave the thread
        // that created it) and every object used was created on it; the draw reads
        // `index_count` indices, all checked against the vertex count in `new`.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.framebuffer));
            gl.use_program(Some(self.program));
            gl.bind_vertex_array(Some(self.vertex_array));
            gl.uniform_matrix_4_f32_slice(Some(&self.clip_from_world_location), false, &clip_from_world);
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
            gl.draw_elements(glow::TRIANGLES, self.index_count, glow::UNSIGNED_INT, 0);
            gl.finish();
        }
    }

    /// Reads the framebuffer back and returns the fraction of pixels that are not the clear
    /// colour, in `[0, 1]`.
    pub fn coverage(&mut self) -> f64 {
        // SAFETY: the context is current and the framebuffer belongs to it; `pixels` holds
        // exactly `width * height * 4` bytes, what an RGBA / UNSIGNED_BYTE read of the whole
        // framebuffer writes with the PACK_ALIGNMENT of 1 set in `new`.
        unsafe {
            self.gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.framebuffer));
            self.gl.read_pixels(
                0,
                0,
                self.width,
                self.height,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelPackData::Slice(Some(self.pixels.as_mut_slice())),
            );
        }
        let total = self.pixels.len() / CLEAR_RGBA8.len();
        let covered = self.pixels.chunks_exact(CLEAR_RGBA8.len()).filter(|pixel| **pixel != CLEAR_RGBA8[..]).count();
        covered as f64 / total as f64
    }

    /// `GL_RENDERER` of the context, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub fn renderer_name(&self) -> String {
        self.renderer.clone()
    }
}

impl Drop for GlPeer {
    fn drop(&mut self) {
        let gl = &self.gl;
        // SAFETY: the context is still current (`session` is dropped after this runs) and all
        // these objects were created on it and are not used afterwards.
        unsafe {
            gl.delete_program(self.program);
            gl.delete_vertex_array(self.vertex_array);
            for buffer in self.buffers {
                gl.delete_buffer(buffer);
            }
            gl.delete_framebuffer(self.framebuffer);
            for renderbuffer in self.renderbuffers {
                gl.delete_renderbuffer(renderbuffer);
            }
        }
    }
}

/// The EGL side of the peer: library, display and a context current on this thread.
///
/// Dropping it releases and destroys the context (which frees every GL object still alive), so
/// a failure half-way through [`GlPeer::new`] leaks nothing. The display is not terminated:
/// EGL displays are per-process singletons without reference counting, and terminating one
/// would pull it from under any other user in the process.
struct EglSession {
    api: Egl,
    display: egl::Display,
    context: egl::Context,
    /// The 1x1 pbuffer made current when surfaceless contexts are not supported.
    surface: Option<egl::Surface>,
}

impl EglSession {
    /// Loads libEGL, opens and initializes a display, and makes an OpenGL ES 3.0 context
    /// current on this thread.
    fn new() -> Result<Self, String> {
        // SAFETY: loading the system's libEGL.so.1 runs only its own initializers; khronos-egl
        // resolves the EGL 1.4 entry points by name, and the library is opened with
        // RTLD_NODELETE, so they stay valid for the life of the process.
        let api = unsafe { Egl::load_required() }.map_err(|error| match error {
            egl::LoadError::Library(error) => {
                format!("libEGL.so.1 not found or not loadable ({error}): {PACKAGES_HINT}")
            }
            error => format!("libEGL.so.1 is unusable: {error}"),
        })?;

        let display = open_display(&api)?;
        api.initialize(display).map_err(|error| format!("eglInitialize failed ({error}): {PACKAGES_HINT}"))?;
        let config = choose_config(&api, display)?;
        api.bind_api(egl::OPENGL_ES_API).map_err(|error| format!("eglBindAPI(EGL_OPENGL_ES_API) failed: {error}"))?;
        let context = api
            .create_context(display, config, None, &[egl::CONTEXT_CLIENT_VERSION, 3, egl::NONE])
            .map_err(|error| format!("creating an OpenGL ES 3.0 context failed: {error}"))?;

        // From here on, dropping `session` cleans up.
        let mut session = Self { api, display, context, surface: None };
        let display_extensions = extension_list(&session.api, Some(display));
        if has_extension(&display_extensions, "EGL_KHR_surfaceless_context") {
            session
                .api
                .make_current(display, None, None, Some(context))
                .map_err(|error| format!("eglMakeCurrent without a surface failed: {error}"))?;
        } else {
            let surface = session
                .api
                .create_pbuffer_surface(display, config, &[egl::WIDTH, 1, egl::HEIGHT, 1, egl::NONE])
                .map_err(|error| format!("no surfaceless contexts and no 1x1 pbuffer either: {error}"))?;
            session.surface = Some(surface);
            session
                .api
                .make_current(display, Some(surface), Some(surface), Some(context))
                .map_err(|error| format!("eglMakeCurrent with a pbuffer failed: {error}"))?;
        }
        Ok(session)
    }
}

impl Drop for EglSession {
    fn drop(&mut self) {
        // Failures are ignored: nothing useful can be done about them during teardown.
        let _ = self.api.make_current(self.display, None, None, None);
        if let Some(surface) = self.surface.take() {
            let _ = self.api.destroy_surface(self.display, surface);
        }
        let _ = self.api.destroy_context(self.display, self.context);
    }
}

/// The surfaceless Mesa display when the client supports it, else `EGL_DEFAULT_DISPLAY`.
fn open_display(api: &Egl) -> Result<egl::Display, String> {
    let client_extensions = extension_list(api, None);
    if has_extension(&client_extensions, "EGL_MESA_platform_surfaceless")
        && let Some(api_1_5) = api.upcast::<egl::EGL1_5>()
    {
        // SAFETY: the surfaceless platform takes no native display: EGL_DEFAULT_DISPLAY (null)
        // is the value its specification requires; the attribute list is terminated.
        let display = unsafe {
            api_1_5.get_platform_display(PLATFORM_SURFACELESS_MESA, egl::DEFAULT_DISPLAY, &[egl::ATTRIB_NONE])
        };
        if let Ok(display) = display {
            return Ok(display);
        }
    }
    // SAFETY: EGL_DEFAULT_DISPLAY is a valid display id on every platform.
    unsafe { api.get_display(egl::DEFAULT_DISPLAY) }.ok_or_else(|| {
        format!(
            "no EGL display (tried EGL_PLATFORM_SURFACELESS_MESA and EGL_DEFAULT_DISPLAY): \
             {PACKAGES_HINT}"
        )
    })
}

/// A config that can render OpenGL ES 3, preferably one that also supports pbuffers (the
/// fallback when surfaceless contexts are missing). Its colour and depth sizes do not matter:
/// the peer draws into its own framebuffer object.
fn choose_config(api: &Egl, display: egl::Display) -> Result<egl::Config, String> {
    let candidates: [&[egl::Int]; 2] = [
        &[egl::RENDERABLE_TYPE, egl::OPENGL_ES3_BIT, egl::SURFACE_TYPE, egl::PBUFFER_BIT, egl::NONE],
        &[egl::RENDERABLE_TYPE, egl::OPENGL_ES3_BIT, egl::SURFACE_TYPE, 0, egl::NONE],
    ];
    for attributes in candidates {
        match api.choose_first_config(display, attributes) {
            Ok(Some(config)) => return Ok(config),
            Ok(None) => {}
            Err(error) => return Err(format!("eglChooseConfig failed: {error}")),
        }
    }
    Err(format!("no EGL config supports OpenGL ES 3: {PACKAGES_HINT}"))
}

/// The EGL extension string of `display`, or the client extensions for `None`; empty when it
/// cannot be queried.
fn extension_list(api: &Egl, display: Option<egl::Display>) -> String {
    api.query_string(display, egl::EXTENSIONS)
        .map(|extensions| extensions.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Whether the space-separated `extensions` list names `extension`.
fn has_extension(extensions: &str, extension: &str) -> bool {
    extensions.split_ascii_whitespace().any(|name| name == extension)
}

/// Checks what the GPU would otherwise read out of bounds, and returns the index count.
fn validate_scene(scene: &PeerScene) -> Result<i32, String> {
    if scene.positions.len() != scene.normals.len() {
        return Err(format!("{} positions but {} normals", scene.positions.len(), scene.normals.len()));
    }
    if !scene.indices.len().is_multiple_of(3) {
        return Err(format!("{} indices is not a whole number of triangles", scene.indices.len()));
    }
    if let Some(&index) = scene.indices.iter().find(|&&index| index as usize >= scene.positions.len()) {
        return Err(format!("index {index} out of range for {} vertices", scene.positions.len()));
    }
    i32::try_from(scene.indices.len()).map_err(|_| format!("{} indices are too many for one draw", scene.indices.len()))
}

/// Compiles and links [`VERTEX_SHADER`] and [`FRAGMENT_SHADER`].
fn compile_program(gl: &glow::Context) -> Result<glow::Program, String> {
    let vertex = compile_shader(gl, glow::VERTEX_SHADER, VERTEX_SHADER, "vertex")?;
    let fragment = compile_shader(gl, glow::FRAGMENT_SHADER, FRAGMENT_SHADER, "fragment")?;
    // SAFETY: the context is current and both shaders were created on it.
    unsafe {
        let program = gl.create_program().map_err(|error| format!("creating a GL program failed: {error}"))?;
        gl.attach_shader(program, vertex);
        gl.attach_shader(program, fragment);
        gl.link_program(program);
        gl.detach_shader(program, vertex);
        gl.detach_shader(program, fragment);
        gl.delete_shader(vertex);
        gl.delete_shader(fragment);
        if gl.get_program_link_status(program) {
            Ok(program)
        } else {
            Err(format!("linking the GL peer's shaders failed: {}", gl.get_program_info_log(program)))
        }
    }
}

/// Compiles one shader stage; `stage` names it in error messages.
fn compile_shader(gl: &glow::Context, kind: u32, source: &str, stage: &str) -> Result<glow::Shader, String> {
    // SAFETY: the context is current; `kind` is a shader stage enum.
    unsafe {
        let shader = gl.create_shader(kind).map_err(|error| format!("creating the {stage} shader failed: {error}"))?;
        gl.shader_source(shader, source);
        gl.compile_shader(shader);
        if gl.get_shader_compile_status(shader) {
            Ok(shader)
        } else {
            Err(format!("compiling the {stage} shader failed: {}", gl.get_shader_info_log(shader)))
        }
    }
}

/// Binds `program`, sets the scene's constant uniforms (colour and light) and returns the
/// location of the per-frame matrix.
fn set_up_program(
    gl: &glow::Context,
    program: glow::Program,
    scene: &PeerScene,
) -> Result<glow::UniformLocation, String> {
    let clip_from_world = uniform_location(gl, program, "u_clip_from_world")?;
    let color = uniform_location(gl, program, "u_color")?;
    let light = uniform_location(gl, program, "u_light")?;
    let [r, g, b] = scene.color;
    let [x, y, z] = scene.light;
    // SAFETY: the context is current and the locations belong to `program`, bound first.
    unsafe {
        gl.use_program(Some(program));
        gl.uniform_3_f32(Some(&color), r, g, b);
        gl.uniform_3_f32(Some(&light), x, y, z);
    }
    Ok(clip_from_world)
}

/// The location of an active uniform of `program`.
fn uniform_location(gl: &glow::Context, program: glow::Program, name: &str) -> Result<glow::UniformLocation, String> {
    // SAFETY: the context is current and `program` is linked.
    unsafe { gl.get_uniform_location(program, name) }
        .ok_or_else(|| format!("the GL peer's program has no uniform {name}"))
}

/// Uploads positions, normals and indices once into buffers described by a vertex array
/// (which also records the index buffer binding).
fn upload_mesh(gl: &glow::Context, scene: &PeerScene) -> Result<(glow::VertexArray, [glow::Buffer; 3]), String> {
    let positions = vec3_bytes(scene.positions);
    let normals = vec3_bytes(scene.normals);
    let indices: Vec<u8> = scene.indices.iter().flat_map(|index| index.to_ne_bytes()).collect();
    // SAFETY: the context is current; each attribute reads three tightly packed f32 per vertex,
    // which is the layout of the uploaded bytes, and the vertex array stays bound while the
    // attributes and the index buffer are recorded into it.
    unsafe {
        let vertex_array =
            gl.create_vertex_array().map_err(|error| format!("creating a vertex array failed: {error}"))?;
        gl.bind_vertex_array(Some(vertex_array));

        let position_buffer = upload_buffer(gl, glow::ARRAY_BUFFER, &positions)?;
        gl.vertex_attrib_pointer_f32(POSITION_LOCATION, 3, glow::FLOAT, false, VEC3_STRIDE, 0);
        gl.enable_vertex_attrib_array(POSITION_LOCATION);

        let normal_buffer = upload_buffer(gl, glow::ARRAY_BUFFER, &normals)?;
        gl.vertex_attrib_pointer_f32(NORMAL_LOCATION, 3, glow::FLOAT, false, VEC3_STRIDE, 0);
        gl.enable_vertex_attrib_array(NORMAL_LOCATION);

        let index_buffer = upload_buffer(gl, glow::ELEMENT_ARRAY_BUFFER, &indices)?;
        Ok((vertex_array, [position_buffer, normal_buffer, index_buffer]))
    }
}

/// Creates a buffer, binds it to `target` (leaving it bound) and fills it with `bytes`.
fn upload_buffer(gl: &glow::Context, target: u32, bytes: &[u8]) -> Result<glow::Buffer, String> {
    // SAFETY: the context is current; glow passes the slice's pointer and length to GL,
    // which copies the data.
    unsafe {
        let buffer = gl.create_buffer().map_err(|error| format!("creating a GL buffer failed: {error}"))?;
        gl.bind_buffer(target, Some(buffer));
        gl.buffer_data_u8_slice(target, bytes, glow::STATIC_DRAW);
        Ok(buffer)
    }
}

/// A framebuffer object with an RGBA8 colour and a 24-bit depth renderbuffer, left bound.
fn create_framebuffer(
    gl: &glow::Context,
    width: i32,
    height: i32,
) -> Result<(glow::Framebuffer, [glow::Renderbuffer; 2]), String> {
    // SAFETY: the context is current; both formats are required renderbuffer formats in
    // OpenGL ES 3.0 and the size was checked to be positive.
    unsafe {
        let framebuffer = gl.create_framebuffer().map_err(|error| format!("creating a framebuffer failed: {error}"))?;
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(framebuffer));
        let attach = |format: u32, attachment: u32| -> Result<glow::Renderbuffer, String> {
            let renderbuffer =
                gl.create_renderbuffer().map_err(|error| format!("creating a renderbuffer failed: {error}"))?;
            gl.bind_renderbuffer(glow::RENDERBUFFER, Some(renderbuffer));
            gl.renderbuffer_storage(glow::RENDERBUFFER, format, width, height);
            gl.framebuffer_renderbuffer(glow::FRAMEBUFFER, attachment, glow::RENDERBUFFER, Some(renderbuffer));
            Ok(renderbuffer)
        };
        let color = attach(glow::RGBA8, glow::COLOR_ATTACHMENT0)?;
        let depth = attach(glow::DEPTH_COMPONENT24, glow::DEPTH_ATTACHMENT)?;
        let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
        if status != glow::FRAMEBUFFER_COMPLETE {
            return Err(format!("the GL peer's {width}x{height} framebuffer is incomplete (status 0x{status:04X})"));
        }
        Ok((framebuffer, [color, depth]))
    }
}

/// State that never changes between frames: viewport, depth test "less" with writes, back-face
/// culling with counter-clockwise front faces, no blending or dithering, the clear values
/// (opaque black, far depth) and byte-aligned pixel reads.
fn set_up_fixed_state(gl: &glow::Context, width: i32, height: i32) {
    // SAFETY: the context is current; all arguments are valid enums and values.
    unsafe {
        gl.viewport(0, 0, width, height);
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(glow::LESS);
        gl.depth_mask(true);
        gl.enable(glow::CULL_FACE);
        gl.cull_face(glow::BACK);
        gl.front_face(glow::CCW);
        gl.disable(glow::BLEND);
        gl.disable(glow::DITHER);
        gl.clear_color(0.0, 0.0, 0.0, 1.0);
        gl.clear_depth_f32(1.0);
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
    }
}

/// The native-endian bytes of `vectors`, three `f32` each, as GL expects them.
fn vec3_bytes(vectors: &[[f32; 3]]) -> Vec<u8> {
    vectors.iter().flatten().flat_map(|component| component.to_ne_bytes()).collect()
}
