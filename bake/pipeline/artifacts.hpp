// Named, typed values that pipeline stages exchange ("fabric", "section/feature_maps", ...).
// A value is immutable once stored and shared by reference between stages.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <typeinfo>
#include <vector>

#include "common/error.hpp"

namespace clothbake::pipeline {

class Artifacts {
 public:
  // Stores `value` under `name`. Throws Error(Internal) if the name is taken.
  template <class T>
  void put(const std::string& name, T value) {
    if (values_.count(name)) throw_internal_error("artifact '" + name + "' is produced twice");
    values_.emplace(name, std::make_shared<const Holder<T>>(std::move(value)));
  }

  // The value stored under `name`. Throws Error(Internal) if it is missing or of another type.
  template <class T>
  const T& get(const std::string& name) const {
    auto it = values_.find(name);
    if (it == values_.end()) throw_internal_error("artifact '" + name + "' is missing");
    const auto* holder = dynamic_cast<const Holder<T>*>(it->second.get());
    if (holder == nullptr)
      throw_internal_error("artifact '" + name + "' is not a " + typeid(T).name());
    return holder->value;
  }

  bool contains(const std::string& name) const { return values_.count(name) != 0; }

  // Names in sorted order (optionally only those starting with `prefix`).
  std::vector<std::string> names(const std::string& prefix = "") const {
    std::vector<std::string> out;
    for (auto it = values_.lower_bound(prefix);
         it != values_.end() && it->first.compare(0, prefix.size(), prefix) == 0; ++it)
      out.push_back(it->first);
    return out;
  }

  // Adds every value of `other` to this set (shared, not copied). Throws Error(Internal) naming
  // the first name present in both.
  void merge(const Artifacts& other) {
    for (const auto& [name, value] : other.values_)
      if (values_.count(name)) throw_internal_error("artifact '" + name + "' is produced twice");
    for (const auto& [name, value] : other.values_)
      values_.emplace(name, value);
  }

  // Moves `name` from `other` into this set (shared, not copied).
  void take(Artifacts& other, const std::string& name) {
    auto it = other.values_.find(name);
    if (it == other.values_.end()) throw_internal_error("artifact '" + name + "' is missing");
    if (values_.count(name)) throw_internal_error("artifact '" + name + "' is produced twice");
    values_.emplace(name, it->second);
  }

 private:
  struct Base {
    virtual ~Base() = default;
  };
  template <class T>
  struct Holder final : Base {
    explicit Holder(T v) : value(std::move(v)) {}
    T value;
  };
  std::map<std::string, std::shared_ptr<const Base>> values_;
};

}  // namespace clothbake::pipeline
