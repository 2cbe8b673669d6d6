// Kinds of raypc::Error that callers may want to tell apart: the CLI prints any Error as one line
// and does not care, but Python maps each kind to its builtin exception (raypc.NotFoundError is a
// FileNotFoundError, raypc.UnknownNameError a KeyError, raypc.OutOfRangeError an IndexError;
// docs/python.md, "Errors"), so that `except KeyError:` works as a Python user expects.
//
// Kept apart from core/error.h so that the few places that raise a kind include this header and
// the rest of the code (and its build) does not change. Every kind is a raypc::Error with the same
// one-line message.
#pragma once

#include "core/error.h"

#include <string>

namespace raypc {

// A file, directory or dataset that is not there.
class NotFoundError : public Error {
public:
    using Error::Error;
};

// A name looked up among a fixed set that does not hold it: a variable of a dataset, a brushed
// variable or coordinate.
class UnknownNameError : public Error {
public:
    using Error::Error;
};

// An index (a step, a level of detail) or a time beyond those that exist.
class OutOfRangeError : public Error {
public:
    using Error::Error;
};

template <typename... Args>
[[noreturn]] void failNotFound(fmt::format_string<Args...> format, Args&&... args)
{
    throw NotFoundError(fmt::format(format, std::forward<Args>(args)...));
}

template <typename... Args>
[[noreturn]] void failUnknownName(fmt::format_string<Args...> format, Args&&... args)
{
    throw UnknownNameError(fmt::format(format, std::forward<Args>(args)...));
}

template <typename... Args>
[[noreturn]] void failOutOfRange(fmt::format_string<Args...> format, Args&&... args)
{
    throw OutOfRangeError(fmt::format(format, std::forward<Args>(args)...));
}

// Throws an error of the same kind as `original` with another message: for code that adds context
// to an error it catches without hiding what kind of failure it was.
[[noreturn]] inline void failLike(const Error& original, const std::string& message)
{
    if (dynamic_cast<const NotFoundError*>(&original))
        throw NotFoundError(message);
    if (dynamic_cast<const UnknownNameError*>(&original))
        throw UnknownNameError(message);
    if (dynamic_cast<const OutOfRangeError*>(&original))
        throw OutOfRangeError(message);
    throw Error(message);
}

}  // namespace raypc
