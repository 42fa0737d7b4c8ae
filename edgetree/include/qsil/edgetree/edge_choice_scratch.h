#pragma once
/// @file edge_choice_scratch.h
/// Scratch memory of the edge choice, passed explicitly (pbrt-v4's ScratchBuffer idea, with typed
/// buffers instead of an arena).

#include <memory>
#include <typeinfo>
#include <typeindex>
#include <utility>
#include <vector>

namespace qsil::edgetree {

/// Buffers that the edge samplers and the contour sets reuse from one query to the next, so that
/// a traversal allocates nothing once they have grown. The caller owns one per thread (a worker's
/// pixel loop, a reverse-mode tile) and hands it over in SilhouetteQuery::scratch; a sampler given
/// none makes its own for the call. Each sampler's source file keys its own buffer type T (a struct
/// of vectors) and clears what it uses: nothing is carried from one query to the next, and one
/// scratch serves one thread at a time.
class EdgeChoiceScratch {
 public:
  EdgeChoiceScratch() = default;
  EdgeChoiceScratch(const EdgeChoiceScratch&) = delete;
  EdgeChoiceScratch& operator=(const EdgeChoiceScratch&) = delete;
  EdgeChoiceScratch(EdgeChoiceScratch&&) noexcept = default;
  EdgeChoiceScratch& operator=(EdgeChoiceScratch&&) noexcept = default;

  /// The buffer of type T (default-constructed on first use, then the same object).
  template <class T>
  T& get() {
    const std::type_index key(typeid(T));
    for (Slot& s : slots_)
      if (s.key == key) return *static_cast<T*>(s.buffer.get());
    slots_.push_back({key, std::unique_ptr<void, void (*)(void*)>(new T(), [](void* b) { delete static_cast<T*>(b); })});
    return *static_cast<T*>(slots_.back().buffer.get());
  }

 private:
  struct Slot {
    std::type_index key;
    std::unique_ptr<void, void (*)(void*)> buffer;
  };
  std::vector<Slot> slots_;
};

/// `scratch`'s buffer of type T, or, without a scratch, the one of `fallback` (a scratch the caller
/// made for this call).
template <class T>
T& scratch_buffer(EdgeChoiceScratch* scratch, EdgeChoiceScratch& fallback) {
  return (scratch ? *scratch : fallback).get<T>();
}

}  // namespace qsil::edgetree
