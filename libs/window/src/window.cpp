#include "relief/window/window.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cstdlib>
#include <optional>
#include <string>
#include <thread>
#include <tuple>
#include <utility>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <fmt/format.h>
#include <imgui.h>

#include "glfw_input.h"

namespace relief::window {

namespace {

// GLFW reports errors through a callback; the last one explains a failure.
std::string g_last_error;
bool g_open = false;  // GLFW is initialised once per process at a time

void on_glfw_error(int, const char* description) {
  g_last_error = description;
}

// The window's frames: an offscreen target recreated at each size, behind a
// RenderTarget whose address stays the same for the window's life.
class ResizableTarget final : public render::RenderTarget {
 public:
  Status resize(int width, int height) {
    if (inner_ && inner_->width() == width && inner_->height() == height) return {};
    inner_.reset();
    inner_ = RELIEF_TRY(render::make_offscreen_target(width, height));
    return {};
  }
  int width() const override { return inner_->width(); }
  int height() const override { return inner_->height(); }
  void bind() override { inner_->bind(); }
  Result<std::vector<uint8_t>> read_rgba() override { return inner_->read_rgba(); }

 private:
  std::unique_ptr<render::RenderTarget> inner_;
};

}  // namespace

struct Window::Impl {
  Window* owner = nullptr;
  GLFWwindow* window = nullptr;
  ResizableTarget target;
  InputHandler handler;
  bool vsync = true, imgui = false, fullscreen = false, keep_screen = false;
  uint64_t events = 0;  // events()
  // present(ui, true): the frame's copy to the screen, its panels and its
  // swap, left to swap_pending().
  std::optional<std::function<void()>> pending;
  uint64_t swaps = 0;
  std::vector<uint8_t> screen;
  int windowed_x = 0, windowed_y = 0, windowed_width = 0, windowed_height = 0;

  ~Impl() {
    if (imgui) {
      ImGui_ImplOpenGL3_Shutdown();
      ImGui_ImplGlfw_Shutdown();
      ImGui::DestroyContext();
    }
    if (window) {
      glfwMakeContextCurrent(window);
      target = ResizableTarget{};  // GL objects go while the context lives
      glfwDestroyWindow(window);
    }
    glfwTerminate();
    g_open = false;
  }
};

namespace {

Window::Impl& impl_of(GLFWwindow* w) {
  return *static_cast<Window::Impl*>(glfwGetWindowUserPointer(w));
}

Window& owner(GLFWwindow* w) {
  return *impl_of(w).owner;
}

// Events that change what the window shows without reaching the handler.
void on_refresh(GLFWwindow* w) {
  ++impl_of(w).events;
}
void on_focus(GLFWwindow* w, int) {
  ++impl_of(w).events;
}

void on_key(GLFWwindow* w, int key, int scancode, int action, int mods) {
  ++impl_of(w).events;
  ImGui_ImplGlfw_KeyCallback(w, key, scancode, action, mods);
  const view::Key k = key_from_glfw(key);
  // Typing into a panel's field is not a command; function keys always are.
  const bool function_key = k >= view::Key::f1 && k <= view::Key::f12;
  if (action == GLFW_REPEAT || (ImGui::GetIO().WantCaptureKeyboard && !function_key)) return;
  view::InputEvent e;
  e.type = action == GLFW_PRESS ? view::InputEvent::Type::key_down : view::InputEvent::Type::key_up;
  e.key = k;
  e.modifiers = modifiers_from_glfw(mods);
  owner(w).deliver(e);
}

void on_char(GLFWwindow* w, unsigned int c) {
  ++impl_of(w).events;
  ImGui_ImplGlfw_CharCallback(w, c);
}

// GLFW gives cursor positions in window coordinates (screen units); frames,
// picking and lenses use framebuffer pixels, more of them on a HiDPI screen.
std::pair<double, double> to_pixels(GLFWwindow* w, double x, double y) {
  int ww = 0, wh = 0, fw = 0, fh = 0;
  glfwGetWindowSize(w, &ww, &wh);
  glfwGetFramebufferSize(w, &fw, &fh);
  return cursor_to_pixels(x, y, ww, wh, fw, fh);
}

void on_mouse_button(GLFWwindow* w, int button, int action, int mods) {
  ++impl_of(w).events;
  ImGui_ImplGlfw_MouseButtonCallback(w, button, action, mods);
  // A press on a panel is the panel's; a release always goes through, so a
  // drag that ends over a panel still ends.
  if (action == GLFW_PRESS && ImGui::GetIO().WantCaptureMouse) return;
  view::InputEvent e;
  e.type =
      action == GLFW_PRESS ? view::InputEvent::Type::mouse_down : view::InputEvent::Type::mouse_up;
  e.button = button_from_glfw(button);
  e.modifiers = modifiers_from_glfw(mods);
  double x = 0, y = 0;
  glfwGetCursorPos(w, &x, &y);
  std::tie(e.x, e.y) = to_pixels(w, x, y);
  owner(w).deliver(e);
}

void on_cursor(GLFWwindow* w, double x, double y) {
  ++impl_of(w).events;
  view::InputEvent e;
  e.type = view::InputEvent::Type::cursor;
  std::tie(e.x, e.y) = to_pixels(w, x, y);
  owner(w).deliver(e);
}

void on_scroll(GLFWwindow* w, double x, double y) {
  ++impl_of(w).events;
  ImGui_ImplGlfw_ScrollCallback(w, x, y);
  if (ImGui::GetIO().WantCaptureMouse) return;
  view::InputEvent e;
  e.type = view::InputEvent::Type::scroll;
  e.x = x, e.y = y;
  owner(w).deliver(e);
}

// The default framebuffer's back buffer (before the swap makes it undefined).
void read_back_buffer(int width, int height, std::vector<uint8_t>& out) {
  std::vector<uint8_t> bottom_up(static_cast<size_t>(width) * height * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, bottom_up.data());
  out.resize(bottom_up.size());
  const size_t row = static_cast<size_t>(width) * 4;
  for (int y = 0; y < height; ++y) {
    std::copy_n(&bottom_up[static_cast<size_t>(height - 1 - y) * row], row,
                &out[static_cast<size_t>(y) * row]);
  }
}

void on_framebuffer_size(GLFWwindow* w, int width, int height) {
  view::InputEvent e;
  e.type = view::InputEvent::Type::resize;
  e.x = width, e.y = height;
  owner(w).deliver(e);
}

}  // namespace

namespace {
// The frame drawn offscreen into the window's back buffer.
void copy_to_screen(render::RenderTarget& target, int width, int height) {
  target.bind();  // the read framebuffer of the copy
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, target.width(), target.height(), 0, 0, width, height, GL_COLOR_BUFFER_BIT,
                    GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}
}  // namespace

Result<std::unique_ptr<Window>> Window::create(const WindowOptions& options) {
  assert(!g_open && "one Window at a time");
  glfwSetErrorCallback(on_glfw_error);
  g_last_error.clear();
  // With a display named, a refused connection can be passing (an X server
  // still tearing down the previous client under load, seen with Xvfb in CI):
  // try a few times before telling the user there is no display.
  bool initialised = glfwInit();
  for (int attempt = 1; !initialised && std::getenv("DISPLAY") && attempt < 5; ++attempt) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200 * attempt));
    g_last_error.clear();
    initialised = glfwInit();
  }
  if (!initialised) {
    return fail(fmt::format(
        "view: cannot open a window ({}); without a display, `relief render` draws stills and "
        "camera paths headless",
        g_last_error.empty() ? "no display" : g_last_error));
  }
  g_open = true;
  auto impl = std::make_unique<Impl>();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  // Frames are drawn offscreen with their own depth buffer; the screen's
  // framebuffer only receives the copy and the panels.
  glfwWindowHint(GLFW_DEPTH_BITS, 0);
  impl->window =
      glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
  if (!impl->window) {
    return fail(fmt::format("view: cannot open a {}x{} window with a GL 4.5 core context ({})",
                            options.width, options.height, g_last_error));
  }
  glfwMakeContextCurrent(impl->window);
  glfwSetWindowUserPointer(impl->window, impl.get());
  int width = 0, height = 0;
  glfwGetFramebufferSize(impl->window, &width, &height);
  RELIEF_CHECK(impl->target.resize(std::max(width, 1), std::max(height, 1)));

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini left in the working directory
  ImGui::StyleColorsDark();
  // Our callbacks forward to ImGui's, then decide what reaches the handler.
  ImGui_ImplGlfw_InitForOpenGL(impl->window, false);
  ImGui_ImplOpenGL3_Init("#version 450");
  impl->imgui = true;
  glfwSetKeyCallback(impl->window, on_key);
  glfwSetCharCallback(impl->window, on_char);
  glfwSetMouseButtonCallback(impl->window, on_mouse_button);
  glfwSetCursorPosCallback(impl->window, on_cursor);
  glfwSetScrollCallback(impl->window, on_scroll);
  glfwSetFramebufferSizeCallback(impl->window, on_framebuffer_size);
  glfwSetWindowRefreshCallback(impl->window, on_refresh);
  glfwSetWindowFocusCallback(impl->window, on_focus);

  std::unique_ptr<Window> w(new Window(std::move(impl)));
  w->impl_->owner = w.get();
  w->set_vsync(options.vsync);
  // The first copy to the screen and the first swap cost 35-90 ms on this
  // project's machines (llvmpipe compiles the copy's shaders; the X server's
  // side of the window is set up): both once now, with a black frame,
  // instead of in the first frames. Not counted in swaps().
  render::RenderTarget& target = w->impl_->target;
  target.bind();
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  copy_to_screen(target, width, height);
  glfwSwapBuffers(w->impl_->window);
  return w;
}

Window::Window(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Window::~Window() = default;

render::RenderTarget& Window::target() {
  return impl_->target;
}

void Window::set_input_handler(InputHandler handler) {
  impl_->handler = std::move(handler);
}

void Window::deliver(const view::InputEvent& event) {
  if (event.type == view::InputEvent::Type::resize && event.x >= 1 && event.y >= 1) {
    swap_pending();  // a frame left to swap is shown before its target goes
    // A failed resize keeps the previous size: the frame is scaled to the window.
    (void)impl_->target.resize(static_cast<int>(event.x), static_cast<int>(event.y));
  }
  ++impl_->events;
  if (impl_->handler) impl_->handler(event);
}

void Window::poll_events() {
  glfwPollEvents();
}

void Window::wait_events(double seconds) {
  glfwWaitEventsTimeout(seconds);
}

void Window::wake() {
  glfwPostEmptyEvent();
}

uint64_t Window::events() const {
  return impl_->events;
}

bool Window::should_close() const {
  return glfwWindowShouldClose(impl_->window);
}

void Window::request_close() {
  glfwSetWindowShouldClose(impl_->window, GLFW_TRUE);
}

void Window::present(const std::function<void()>& ui, bool defer_swap) {
  impl_->pending = ui;
  if (!defer_swap) swap_pending();
}

void Window::swap_pending() {
  if (!impl_->pending) return;
  const std::function<void()> ui = std::move(*impl_->pending);
  impl_->pending.reset();
  int width = 0, height = 0;
  glfwGetFramebufferSize(impl_->window, &width, &height);
  // The copy reads the target, so it waits for the GL to finish drawing it
  // (llvmpipe): hence it is deferred with the swap.
  copy_to_screen(impl_->target, width, height);
  glViewport(0, 0, width, height);
  if (ui) {
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    ui();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  }
  if (impl_->keep_screen) read_back_buffer(width, height, impl_->screen);
  glfwSwapBuffers(impl_->window);
  ++impl_->swaps;
}

bool Window::swap_is_pending() const {
  return impl_->pending.has_value();
}

uint64_t Window::swaps() const {
  return impl_->swaps;
}

void Window::set_keep_screen(bool on) {
  impl_->keep_screen = on;
  if (!on) impl_->screen.clear();
}

const std::vector<uint8_t>& Window::screen() const {
  return impl_->screen;
}

void Window::set_vsync(bool on) {
  impl_->vsync = on;
  glfwSwapInterval(on ? 1 : 0);
}

bool Window::vsync() const {
  return impl_->vsync;
}

void Window::toggle_fullscreen() {
  Impl& m = *impl_;
  if (!m.fullscreen) {
    GLFWmonitor* monitor = glfwGetPrimaryMonitor();
    const GLFWvidmode* mode = monitor ? glfwGetVideoMode(monitor) : nullptr;
    if (!mode) return;
    glfwGetWindowPos(m.window, &m.windowed_x, &m.windowed_y);
    glfwGetWindowSize(m.window, &m.windowed_width, &m.windowed_height);
    glfwSetWindowMonitor(m.window, monitor, 0, 0, mode->width, mode->height, mode->refreshRate);
  } else {
    glfwSetWindowMonitor(m.window, nullptr, m.windowed_x, m.windowed_y, m.windowed_width,
                         m.windowed_height, 0);
  }
  m.fullscreen = !m.fullscreen;
  set_vsync(m.vsync);  // some systems reset the swap interval with the mode
}

bool Window::fullscreen() const {
  return impl_->fullscreen;
}

bool Window::software_renderer() const {
  const std::string r = renderer();
  return r.find("llvmpipe") != std::string::npos || r.find("softpipe") != std::string::npos;
}

std::string Window::renderer() const {
  auto text = [](GLenum name) {
    const auto* s = reinterpret_cast<const char*>(glGetString(name));
    return std::string(s ? s : "?");
  };
  return text(GL_RENDERER) + ", " + text(GL_VERSION);
}

}  // namespace relief::window
