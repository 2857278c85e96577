// Named, typed values that pipeline stages exchange ("fabric", "section/feature_maps", ...).
// A value is immutable once stored and shared by reference between stages.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
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

  // Stores a value of type `type` that is produced on first access: `load` must put it under
  // `name` into the set it is given (the cache decodes a large output only when a stage reads
  // it). What `load` throws propagates from get(), and the next get() calls it again.
  void put_deferred(const std::string& name, const std::type_info& type,
                    std::function<void(Artifacts&)> load) {
    if (values_.count(name)) throw_internal_error("artifact '" + name + "' is produced twice");
    values_.emplace(name, std::make_shared<const Deferred>(name, type, std::move(load)));
  }

  // The value stored under `name`. Throws Error(Internal) if it is missing or of another type.
  template <class T>
  const T& get(const std::string& name) const {
    auto it = values_.find(name);
    if (it == values_.end()) throw_internal_error("artifact '" + name + "' is missing");
    const Base* base = it->second.get();
    const auto* deferred = dynamic_cast<const Deferred*>(base);
    if (deferred) base = deferred->resolve();
    const auto* holder = dynamic_cast<const Holder<T>*>(base);
    if (holder == nullptr && deferred)  // a cache entry that names another codec: bad input
      throw Error(ExitCode::Input,
                  "artifact '" + name + "' from the cache is not a " + typeid(T).name());
    if (holder == nullptr)
      throw_internal_error("artifact '" + name + "' is not a " + typeid(T).name());
    return holder->value;
  }

  bool contains(const std::string& name) const { return values_.count(name) != 0; }

  // The type of the value stored under `name` (for type-keyed serialisers: bake/cache). Throws
  // Error(Internal) if it is missing.
  const std::type_info& type_of(const std::string& name) const {
    auto it = values_.find(name);
    if (it == values_.end()) throw_internal_error("artifact '" + name + "' is missing");
    return it->second->type();
  }

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
    virtual const std::type_info& type() const = 0;
  };
  template <class T>
  struct Holder final : Base {
    explicit Holder(T v) : value(std::move(v)) {}
    const std::type_info& type() const override { return typeid(T); }
    T value;
  };
  struct Deferred final : Base {
    Deferred(std::string n, const std::type_info& t, std::function<void(Artifacts&)> l)
        : name(std::move(n)), stored_type(t), load(std::move(l)) {}
    const std::type_info& type() const override { return stored_type; }
    const Base* resolve() const {
      std::lock_guard<std::mutex> guard(mutex);
      if (!value) {
        Artifacts loaded;
        load(loaded);
        auto it = loaded.values_.find(name);
        if (it == loaded.values_.end() || it->second->type() != stored_type)
          throw_internal_error("deferred artifact '" + name + "' did not load");
        value = it->second;
      }
      return value.get();
    }
    std::string name;
    const std::type_info& stored_type;
    std::function<void(Artifacts&)> load;
    mutable std::mutex mutex;
    mutable std::shared_ptr<const Base> value;
  };
  std::map<std::string, std::shared_ptr<const Base>> values_;
};

}  // namespace clothbake::pipeline
