#pragma once
// A window on the screen with a GL 4.5 core context (GLFW; the only user of
// GLFW and Dear ImGui in relief, both kept out of this header). The context
// is current on the thread that created the window, which owns it: every call
// is made on that thread.
//
// Frames are drawn into target(): an offscreen framebuffer of the window's
// size with the headless target's formats (so a window frame equals the
// headless still of its camera), copied to the screen by present(), which
// then draws the user interface over it. Screenshots read the target:
// terrain only, without the panels.
//
// Input: GLFW's callbacks translate their events into view::InputEvent and
// pass them to deliver(), the one path by which input reaches the handler;
// tests call deliver() with scripted events. Cursor positions are in
// framebuffer pixels, as frames and picking are (GLFW reports window
// coordinates, which differ from them on HiDPI screens).
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/render/render_target.h"
#include "relief/view/input.h"

namespace relief::window {

struct WindowOptions {
  int width = 1280, height = 720;  // framebuffer pixels
  std::string title = "relief";
  bool vsync = true;
};

class Window {
 public:
  // Fails with a one-line message when there is no display (no DISPLAY, or
  // the X server refuses) or no GL 4.5 core context.
  static Result<std::unique_ptr<Window>> create(const WindowOptions& options);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  // Where frames are drawn; resized with the window's framebuffer.
  render::RenderTarget& target();

  using InputHandler = std::function<void(const view::InputEvent&)>;
  void set_input_handler(InputHandler handler);
  // Resize events resize the target first; every event then goes to the handler.
  void deliver(const view::InputEvent& event);
  // Processes the window system's pending events (through deliver()).
  void poll_events();
  // Waits up to `seconds` for an event or a wake(), then processes what is
  // pending: an idle viewer's poll_events().
  void wait_events(double seconds);
  // Ends a wait_events() now or, if none is waiting, the next one at once.
  // Thread-safe: the scene's loaders call it when a tile arrives.
  void wake();
  // Events seen so far: input (also what the panels take), resizes,
  // exposures, focus changes and deliver()ed events. A still viewer redraws
  // when it changes.
  uint64_t events() const;

  // The window was closed (its close button) or request_close() was called.
  bool should_close() const;
  void request_close();

  // Copies the target to the screen, draws `ui` (Dear ImGui calls, may be
  // empty) over it and swaps buffers. With `defer_swap` all three wait for
  // swap_pending() (the copy waits for the GL to finish drawing the target:
  // llvmpipe rasterises on its own threads), so the caller can work (the
  // next frame's refinement) meanwhile (docs/viewer.md, "Overlap"). `ui` is
  // called then, and what it uses must still be there.
  void present(const std::function<void()>& ui, bool defer_swap = false);
  // Copies, draws the panels of and swaps the frame present(ui, true) left, if any.
  void swap_pending();
  bool swap_is_pending() const;
  uint64_t swaps() const;  // buffer swaps so far

  // While on, present() keeps a copy of what it puts on the screen (frame
  // and panels; a read-back per frame, so off by default): screen() returns
  // it, RGBA8 top row first, the window's framebuffer size (empty before).
  void set_keep_screen(bool on);
  const std::vector<uint8_t>& screen() const;

  void set_vsync(bool on);
  bool vsync() const;
  void toggle_fullscreen();
  bool fullscreen() const;
  // GL_RENDERER and GL_VERSION of the context.
  std::string renderer() const;
  // Whether that is a rasteriser on the CPU (Mesa's llvmpipe or softpipe).
  bool software_renderer() const;

  struct Impl;

 private:
  explicit Window(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::window
