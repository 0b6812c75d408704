#pragma once
// Indexed min-heap of collapse candidates (Gasparello 2007 §2: each edge stores its heap position
// so update and remove are O(log n) without searching). Ordered by cost, then by id, so the
// collapse order never depends on heap layout or insertion history. The heap is 8-ary and laid
// out so that the eight children of a node fill exactly one 64-byte cache line: a third of the
// depth of a binary heap, one line per level. Once a million-edge heap no longer fits in cache,
// the lines touched (and the position updates of the entries moved, one per level) are what
// costs, not the extra comparisons (4-ary with unaligned children: docs/simplify.md).
//
// Next to each id's heap position the queue keeps a float the simplifier looks up with it (the
// edge's point-distance penalty), so one random access serves both.

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <vector>

#include "core/large_array.h"

namespace lodbake::detail {

class CollapseQueue {
public:
    static constexpr uint32_t kAbsent = 0xffffffffu;

    /// Ids are in [0, id_capacity).
    explicit CollapseQueue(size_t id_capacity = 0) : heap_(kPad, Entry{0.0f, 0}), slot_(id_capacity, Slot{kAbsent, 0.0f}) {}

    void reserve(size_t n) { heap_.reserve(n + kPad); }
    bool empty() const { return heap_.size() == kPad; }
    size_t size() const { return heap_.size() - kPad; }
    bool contains(uint32_t id) const { return pos(id) != kAbsent; }
    uint32_t topId() const { return at(0).id; }
    /// The smallest child of the root (the top after a pop if nothing else changes), or kAbsent.
    uint32_t secondId() const {
        const uint32_t n = uint32_t(size());
        if (n < 2) return kAbsent;
        const uint32_t last = std::min(kArity + 1, n);
        uint32_t child = 1;
        for (uint32_t k = 2; k < last; ++k)
            if (less(at(k), at(child))) child = k;
        return at(child).id;
    }
    float topCost() const { return at(0).cost; }
    float cost(uint32_t id) const { return at(pos(id)).cost; }

    /// Per-id value owned by the caller, kept whether or not the id is queued (initially 0).
    float payload(uint32_t id) const { return slot_[id].payload; }
    void setPayload(uint32_t id, float value) { slot_[id].payload = value; }

    /// Hint that `id` is about to be looked up (its slot is a random access into a large array).
    void prefetch(uint32_t id) const {
#if defined(__GNUC__)
        __builtin_prefetch(&slot_[id]);
#else
        (void)id;
#endif
    }

    /// Hint that the heap entry of `id` is about to be read (set() or remove() of a queued id reads
    /// it first: a random access into the heap). Reads the id's slot, so prefetch() that first.
    void prefetchEntry(uint32_t id) const {
#if defined(__GNUC__)
        const uint32_t i = pos(id);
        if (i != kAbsent) __builtin_prefetch(&at(i));
#else
        (void)id;
#endif
    }

    /// Inserts `id` or changes its cost if present.
    void set(uint32_t id, float cost) {
        uint32_t i = pos(id);
        if (i == kAbsent) {
            i = uint32_t(size());
            assert(i < kAbsent);
            heap_.push_back({cost, id});
            slot_[id].pos = i;
            siftUp(i);
            return;
        }
        const Entry old = at(i);
        at(i).cost = cost;
        if (less(at(i), old))
            siftUp(i);
        else
            siftDown(i);
    }

    /// Bulk construction: append ids that are not yet present with pushUnordered, then call
    /// heapify once (O(n) instead of n sifts). No other call may come in between.
    void pushUnordered(uint32_t id, float cost) {
        slot_[id].pos = uint32_t(size());
        heap_.push_back({cost, id});
    }
    void heapify() {
        if (size() < 2) return;
        for (uint32_t i = uint32_t((size() - 2) / kArity + 1); i-- > 0;) siftDown(i);
    }

    /// Removes `id` if present.
    void remove(uint32_t id) {
        const uint32_t i = pos(id);
        slot_[id].pos = kAbsent;
        if (i == kAbsent) return;
        const uint32_t last = uint32_t(size() - 1);
        if (i == last) {
            heap_.pop_back();
            return;
        }
        const Entry moved = at(last);
        heap_.pop_back();
        at(i) = moved;
        setPos(moved.id, i);
        if (i > 0 && less(moved, at((i - 1) / kArity)))
            siftUp(i);
        else
            siftDown(i);
    }

    uint32_t pop() {
        const uint32_t id = at(0).id;
        remove(id);
        return id;
    }

    /// True when the heap order and the position index agree (for tests).
    bool isConsistent() const {
        for (size_t i = 0; i < size(); ++i) {
            if (pos(at(i).id) != i) return false;
            if (i > 0 && less(at(i), at((i - 1) / kArity))) return false;
        }
        return true;
    }

private:
    static constexpr uint32_t kArity = 8;
    // heap_ starts with kPad unused entries: node i is heap_[i + kPad], so the children of node i,
    // 8i+1 .. 8i+8, sit at heap_[8(i+1) .. 8(i+1)+7], one aligned 64-byte line when heap_'s storage
    // is 64-byte aligned (LargeArray allocations above 2 MB are; smaller heaps stay in cache).
    static constexpr uint32_t kPad = 7;
    struct Entry {
        float cost;
        uint32_t id;
    };
    struct Slot {
        uint32_t pos; // heap index or kAbsent
        float payload;
    };
    static bool less(const Entry& a, const Entry& b) { return a.cost < b.cost || (a.cost == b.cost && a.id < b.id); }

    Entry& at(uint32_t i) { return heap_[i + kPad]; }
    const Entry& at(uint32_t i) const { return heap_[i + kPad]; }
    uint32_t pos(uint32_t id) const { return slot_[id].pos; }
    void setPos(uint32_t id, uint32_t i) { slot_[id].pos = i; }

    void siftUp(uint32_t i) {
        const Entry e = at(i);
        while (i > 0) {
            const uint32_t parent = (i - 1) / kArity;
            if (!less(e, at(parent))) break;
            at(i) = at(parent);
            setPos(at(i).id, i);
            i = parent;
        }
        at(i) = e;
        setPos(e.id, i);
    }

    void siftDown(uint32_t i) {
        const Entry e = at(i);
        const uint32_t n = uint32_t(size());
        for (;;) {
            const uint32_t first = kArity * i + 1;
            if (first >= n) break;
            const uint32_t last = std::min(first + kArity, n);
            uint32_t child = first;
            for (uint32_t k = first + 1; k < last; ++k)
                if (less(at(k), at(child))) child = k;
            if (!less(at(child), e)) break;
            at(i) = at(child);
            setPos(at(i).id, i);
            i = child;
        }
        at(i) = e;
        setPos(e.id, i);
    }

    LargeArray<Entry> heap_;
    LargeArray<Slot> slot_;
};

} // namespace lodbake::detail
