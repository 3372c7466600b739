/* draw.c: Mesa's llvmpipe drawing a prepared mesh (prep/, file layout in prep/src/main.rs) in one
 * additive pass: an R32F colour buffer, blending ONE + ONE, no depth test, no culling, every
 * fragment adding 1.0. The image is the depth complexity.
 *
 *   draw SCENE FRAMES [COUNTS_OUT]
 *
 * Headless: EGL on Mesa's surfaceless platform, an OpenGL 3.3 core context, a framebuffer object.
 * Run with LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe (compare.sh does); LP_NUM_THREADS sets
 * llvmpipe's rasterizer threads (default: one per CPU).
 *
 * Each timed frame is glClear + glDrawElements + glFinish (the vertex shader runs on every vertex
 * each frame; the buffers are uploaded once). One untimed warm-up frame first. Prints one JSON
 * line: median, min, max ms, the fragment total (sum of the image) and the renderer string.
 * COUNTS_OUT gets the per-pixel counts as W x H little-endian u32, row 0 at the top (fragsim's
 * layout), from one more frame read back with glReadPixels.
 */
#define GL_GLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glcorearb.h>

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static void die(const char *what) {
    fprintf(stderr, "draw: %s\n", what);
    exit(1);
}

static double now_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static GLuint shader(GLenum kind, const char *src) {
    GLuint s = glCreateShader(kind);
    glShaderSource(s, 1, &src, NULL);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[2048];
        glGetShaderInfoLog(s, sizeof log, NULL, log);
        fprintf(stderr, "%s\n", log);
        die("shader compile failed");
    }
    return s;
}

static const char *VS = "#version 330 core\n"
                        "layout(location = 0) in vec3 position;\n"
                        "uniform mat4 mvp;\n"
                        "void main() { gl_Position = mvp * vec4(position, 1.0); }\n";
static const char *FS = "#version 330 core\n"
                        "out vec4 colour;\n"
                        "void main() { colour = vec4(1.0, 0.0, 0.0, 0.0); }\n";

int main(int argc, char **argv) {
    if (argc < 3) die("usage: draw SCENE FRAMES [COUNTS_OUT]");
    int frames = atoi(argv[2]);
    if (frames < 1) die("FRAMES must be at least 1");

    /* The prepared scene. */
    FILE *f = fopen(argv[1], "rb");
    if (!f) die("cannot open the scene");
    char magic[8];
    uint32_t head[4];
    float matrix[16];
    if (fread(magic, 1, 8, f) != 8 || memcmp(magic, "FSLPIPE1", 8) != 0) die("not a prep scene");
    if (fread(head, 4, 4, f) != 4 || fread(matrix, 4, 16, f) != 16) die("truncated header");
    uint32_t width = head[0], height = head[1], nverts = head[2], ntris = head[3];
    float *positions = malloc((size_t)nverts * 12);
    uint32_t *indices = malloc((size_t)ntris * 12);
    if (!positions || !indices) die("out of memory");
    if (fread(positions, 12, nverts, f) != nverts || fread(indices, 12, ntris, f) != ntris)
        die("truncated scene");
    fclose(f);

    /* EGL, surfaceless, desktop GL 3.3 core. */
    PFNEGLGETPLATFORMDISPLAYEXTPROC get_display =
        (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
    if (!get_display) die("no eglGetPlatformDisplayEXT");
    EGLDisplay dpy = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
    if (dpy == EGL_NO_DISPLAY) die("no surfaceless EGL display (EGL_MESA_platform_surfaceless)");
    EGLint major, minor;
    if (!eglInitialize(dpy, &major, &minor)) die("eglInitialize failed");
    if (!eglBindAPI(EGL_OPENGL_API)) die("eglBindAPI(EGL_OPENGL_API) failed");
    const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                  EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext ctx = eglCreateContext(dpy, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, ctx_attribs);
    if (ctx == EGL_NO_CONTEXT) die("eglCreateContext failed (EGL_KHR_no_config_context?)");
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) die("eglMakeCurrent failed");

    /* Target: an R32F texture in a framebuffer object. */
    GLuint tex, fbo;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, (GLsizei)width, (GLsizei)height, 0, GL_RED, GL_FLOAT,
                 NULL);
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        die("R32F framebuffer incomplete");
    glViewport(0, 0, (GLsizei)width, (GLsizei)height);

    /* The mesh, uploaded once. */
    GLuint vao, vbo, ibo;
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(1, &vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)nverts * 12, positions, GL_STATIC_DRAW);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 12, (void *)0);
    glEnableVertexAttribArray(0);
    glGenBuffers(1, &ibo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)ntris * 12, indices, GL_STATIC_DRAW);

    GLuint prog = glCreateProgram();
    glAttachShader(prog, shader(GL_VERTEX_SHADER, VS));
    glAttachShader(prog, shader(GL_FRAGMENT_SHADER, FS));
    glLinkProgram(prog);
    GLint linked = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &linked);
    if (!linked) die("link failed");
    glUseProgram(prog);
    glUniformMatrix4fv(glGetUniformLocation(prog, "mvp"), 1, GL_FALSE, matrix);

    /* One additive pass: no depth, no culling, ONE + ONE. */
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glDisable(GL_DITHER);
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFunc(GL_ONE, GL_ONE);
    glClearColor(0, 0, 0, 0);

    GLsizei count = (GLsizei)(ntris * 3);
    double *ms = malloc(sizeof(double) * (size_t)frames);
    for (int i = -1; i < frames; i++) {
        double t0 = now_ms();
        glClear(GL_COLOR_BUFFER_BIT);
        glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, (void *)0);
        glFinish();
        double t1 = now_ms();
        if (i >= 0) ms[i] = t1 - t0;
    }
    if (glGetError() != GL_NO_ERROR) die("GL error while drawing");

    /* One more frame, read back. */
    glClear(GL_COLOR_BUFFER_BIT);
    glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, (void *)0);
    float *image = malloc(sizeof(float) * (size_t)width * height);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, (GLsizei)width, (GLsizei)height, GL_RED, GL_FLOAT, image);
    if (glGetError() != GL_NO_ERROR) die("GL error while reading back");
    uint32_t *counts = malloc(sizeof(uint32_t) * (size_t)width * height);
    uint64_t fragments = 0;
    uint32_t max_count = 0, covered = 0;
    for (uint32_t y = 0; y < height; y++) {
        for (uint32_t x = 0; x < width; x++) {
            float v = image[(size_t)y * width + x];
            uint32_t c = (uint32_t)v;
            if ((float)c != v) die("a pixel holds a non-integer count");
            /* GL row 0 is the bottom; fragsim's row 0 is the top. */
            counts[(size_t)(height - 1 - y) * width + x] = c;
            fragments += c;
            if (c > max_count) max_count = c;
            if (c) covered++;
        }
    }
    if (argc > 3) {
        FILE *o = fopen(argv[3], "wb");
        if (!o || fwrite(counts, 4, (size_t)width * height, o) != (size_t)width * height)
            die("cannot write the counts");
        fclose(o);
    }

    double sorted[frames];
    memcpy(sorted, ms, sizeof(double) * (size_t)frames);
    qsort(sorted, (size_t)frames, sizeof(double), cmp_double);
    double median = frames % 2 ? sorted[frames / 2]
                               : 0.5 * (sorted[frames / 2 - 1] + sorted[frames / 2]);
    const char *threads = getenv("LP_NUM_THREADS");
    printf("{\"renderer\": \"%s\", \"lp_num_threads\": \"%s\", \"width\": %u, \"height\": %u, "
           "\"triangles\": %u, \"frames\": %d, \"median_ms\": %.3f, \"min_ms\": %.3f, "
           "\"max_ms\": %.3f, \"fragments\": %llu, \"covered_pixels\": %u, "
           "\"max_depth_complexity\": %u}\n",
           (const char *)glGetString(GL_RENDERER), threads ? threads : "default", width, height,
           ntris, frames, median, sorted[0], sorted[frames - 1], (unsigned long long)fragments,
           covered, max_count);

    eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(dpy, ctx);
    eglTerminate(dpy);
    return 0;
}
