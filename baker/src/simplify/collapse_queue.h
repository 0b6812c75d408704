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
#include <cstring>
#include <vector>

#include "core/large_array.h"

namespace lodbake::detail {

namespace collapse_heap {
// The heap entries and per-id slots shared by CollapseQueue and the part heaps of a partitioned
// round (PartHeap): one sift implementation for both.
struct Entry {
    float cost;
    uint32_t id;
};
struct Slot {
    uint32_t pos; // heap index or kAbsent
    float payload;
};
constexpr uint32_t kArity = 8;
constexpr uint32_t kAbsent = 0xffffffffu;
inline bool less(const Entry& a, const Entry& b) { return a.cost < b.cost || (a.cost == b.cost && a.id < b.id); }

// `at` is node 0 of a heap of n entries; the slot of id x is slot[x].
inline void siftUp(Entry* at, Slot* slot, uint32_t i) {
    const Entry e = at[i];
    while (i > 0) {
        const uint32_t parent = (i - 1) / kArity;
        if (!less(e, at[parent])) break;
        at[i] = at[parent];
        slot[at[i].id].pos = i;
        i = parent;
    }
    at[i] = e;
    slot[e.id].pos = i;
}

inline void siftDown(Entry* at, Slot* slot, uint32_t n, uint32_t i) {
    const Entry e = at[i];
    for (;;) {
        const uint32_t first = kArity * i + 1;
        if (first >= n) break;
        const uint32_t last = std::min(first + kArity, n);
        uint32_t child = first;
        for (uint32_t k = first + 1; k < last; ++k)
            if (less(at[k], at[child])) child = k;
        if (!less(at[child], e)) break;
        at[i] = at[child];
        slot[at[i].id].pos = i;
        i = child;
    }
    at[i] = e;
    slot[e.id].pos = i;
}

// The smallest child of the root of a heap of n entries (the top after a pop if nothing else
// changes), or kAbsent.
inline uint32_t secondId(const Entry* at, uint32_t n) {
    if (n < 2) return kAbsent;
    const uint32_t last = std::min(kArity + 1, n);
    uint32_t child = 1;
    for (uint32_t k = 2; k < last; ++k)
        if (less(at[k], at[child])) child = k;
    return at[child].id;
}

// Gives the entry at i a new cost and restores the order.
inline void update(Entry* at, Slot* slot, uint32_t n, uint32_t i, float cost) {
    const Entry old = at[i];
    at[i].cost = cost;
    if (less(at[i], old))
        siftUp(at, slot, i);
    else
        siftDown(at, slot, n, i);
}

// Removes `id` if present from a heap of n entries (its last entry fills the gap); returns the new
// count.
inline uint32_t remove(Entry* at, Slot* slot, uint32_t n, uint32_t id) {
    const uint32_t i = slot[id].pos;
    slot[id].pos = kAbsent;
    if (i == kAbsent) return n;
    const uint32_t last = n - 1;
    if (i == last) return last;
    at[i] = at[last];
    slot[at[i].id].pos = i;
    if (i > 0 && less(at[i], at[(i - 1) / kArity]))
        siftUp(at, slot, i);
    else
        siftDown(at, slot, last, i);
    return last;
}

// True when the heap order and the position index agree (for tests).
inline bool isConsistent(const Entry* at, const Slot* slot, uint32_t n) {
    for (uint32_t i = 0; i < n; ++i) {
        if (slot[at[i].id].pos != i) return false;
        if (i > 0 && less(at[i], at[(i - 1) / kArity])) return false;
    }
    return true;
}
} // namespace collapse_heap

class PartHeap;

class CollapseQueue {
public:
    static constexpr uint32_t kAbsent = 0xffffffffu;

    /// Ids are in [0, id_capacity).
    explicit CollapseQueue(size_t id_capacity = 0) : heap_(kPad, Entry{0.0f, 0}), slot_(id_capacity, Slot{kAbsent, 0.0f}) {}

    /// Room for n ids without growing, and for the alignment of the part heaps of a split().
    void reserve(size_t n) { heap_.reserve(n + kPad + kSplitSlack); }
    bool empty() const { return heap_.size() == kPad; }
    size_t size() const { return heap_.size() - kPad; }
    bool contains(uint32_t id) const { return pos(id) != kAbsent; }
    uint32_t topId() const { return at(0).id; }
    /// The smallest child of the root (the top after a pop if nothing else changes), or kAbsent.
    uint32_t secondId() const { return collapse_heap::secondId(base(), uint32_t(size())); }
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
        collapse_heap::update(base(), slot_.data(), uint32_t(size()), i, cost);
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
        heap_.resize(size_t(collapse_heap::remove(base(), slot_.data(), uint32_t(size()), id)) + kPad);
    }

    uint32_t pop() {
        const uint32_t id = at(0).id;
        remove(id);
        return id;
    }

    /// True when the heap order and the position index agree (for tests).
    bool isConsistent() const { return collapse_heap::isConsistent(base(), slot_.data(), uint32_t(size())); }

    /// Partitioned rounds (EdgeCollapser::run): moves every queued id x with p = part_of(x) <
    /// part_count into part heap p, laid out in this queue's storage after the ids that stay
    /// (part_of(x) >= part_count). capacity[p] is the most ids part p will hold at once. Returns false,
    /// changing nothing, when the parts do not fit in the storage reserved. Until merge() the queue
    /// itself may not be used; the part heaps share its per-id slots (their ids must be disjoint).
    template <class PartOf>
    bool split(PartOf part_of, const uint32_t* capacity, PartHeap* parts, uint32_t part_count);
    /// The same; the part heaps are built (their entries' positions set, then heap order) by
    /// for_parts(part_count, build), which calls build(p) once for every part p, in any order or at once
    /// (the parts own disjoint regions and ids).
    template <class PartOf, class ForParts>
    bool split(PartOf part_of, const uint32_t* capacity, PartHeap* parts, uint32_t part_count, ForParts for_parts);
    /// Ends a split: the part heaps' ids and the ones that stayed form one queue again.
    void merge(const PartHeap* parts, uint32_t part_count);

private:
    using Entry = collapse_heap::Entry;
    using Slot = collapse_heap::Slot;
    static constexpr uint32_t kArity = collapse_heap::kArity;
    // heap_ starts with kPad unused entries: node i is heap_[i + kPad], so the children of node i,
    // 8i+1 .. 8i+8, sit at heap_[8(i+1) .. 8(i+1)+7], one aligned 64-byte line when heap_'s storage
    // is 64-byte aligned (LargeArray allocations above 2 MB are; smaller heaps stay in cache).
    static constexpr uint32_t kPad = 7;
    // split() starts each part's region on a multiple of 8 entries, with its own kPad: at most 14
    // entries per part beyond the ids themselves (512 bytes for up to 4 parts).
    static constexpr uint32_t kSplitSlack = 64;

    // Node 0 (one past the padding: valid as a pointer also when the heap is empty).
    Entry* base() { return heap_.data() + kPad; }
    const Entry* base() const { return heap_.data() + kPad; }
    Entry& at(uint32_t i) { return heap_[i + kPad]; }
    const Entry& at(uint32_t i) const { return heap_[i + kPad]; }
    uint32_t pos(uint32_t id) const { return slot_[id].pos; }
    void setPos(uint32_t id, uint32_t i) { slot_[id].pos = i; }

    void siftUp(uint32_t i) { collapse_heap::siftUp(base(), slot_.data(), i); }
    void siftDown(uint32_t i) { collapse_heap::siftDown(base(), slot_.data(), uint32_t(size()), i); }

    LargeArray<Entry> heap_;
    LargeArray<Slot> slot_;
    uint32_t rest_size_ = 0; // between split() and merge(): the ids that stayed
};

/// One part's heap during a partitioned round: a region of a CollapseQueue's storage and its slots
/// (CollapseQueue::split). Same order and operations as CollapseQueue; it never grows.
class PartHeap {
public:
    static constexpr uint32_t kAbsent = collapse_heap::kAbsent;

    bool empty() const { return size_ == 0; }
    size_t size() const { return size_; }
    uint32_t topId() const { return at_[0].id; }
    float topCost() const { return at_[0].cost; }
    /// Calls fn(cost) for every queued id, in heap order.
    template <class Fn> void forEachCost(Fn&& fn) const {
        for (uint32_t i = 0; i < size_; ++i) fn(at_[i].cost);
    }
    uint32_t secondId() const { return collapse_heap::secondId(at_, size_); }
    float payload(uint32_t id) const { return slot_[id].payload; }
    void setPayload(uint32_t id, float value) { slot_[id].payload = value; }
    void prefetchEntry(uint32_t id) const {
#if defined(__GNUC__)
        const uint32_t i = slot_[id].pos;
        if (i != kAbsent && i < size_) __builtin_prefetch(&at_[i]);
#else
        (void)id;
#endif
    }

    void set(uint32_t id, float cost) {
        uint32_t i = slot_[id].pos;
        if (i == kAbsent) {
            assert(size_ < capacity_);
            i = size_++;
            at_[i] = {cost, id};
            collapse_heap::siftUp(at_, slot_, i);
            return;
        }
        collapse_heap::update(at_, slot_, size_, i, cost);
    }

    void remove(uint32_t id) { size_ = collapse_heap::remove(at_, slot_, size_, id); }

    /// True when the heap order and the position index agree (for tests).
    bool isConsistent() const { return collapse_heap::isConsistent(at_, slot_, size_); }

private:
    friend class CollapseQueue;
    collapse_heap::Entry* at_ = nullptr; // node 0
    collapse_heap::Slot* slot_ = nullptr;
    uint32_t size_ = 0, capacity_ = 0;
};

template <class PartOf>
bool CollapseQueue::split(PartOf part_of, const uint32_t* capacity, PartHeap* parts, uint32_t part_count) {
    return split(part_of, capacity, parts, part_count, [](uint32_t count, const auto& build) {
        for (uint32_t p = 0; p < count; ++p) build(p);
    });
}

template <class PartOf, class ForParts>
bool CollapseQueue::split(PartOf part_of, const uint32_t* capacity, PartHeap* parts, uint32_t part_count,
                          ForParts for_parts) {
    // Region of part p: heap_[start_p, start_p + kPad + capacity[p]), start_p a multiple of 8, so that
    // its node i sits at start_p + kPad + i with the same cache-line alignment as the whole queue's.
    const uint32_t n = uint32_t(size());
    uint32_t counts[8] = {};
    assert(part_count <= 8);
    uint32_t rest = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t p = part_of(at(i).id);
        if (p < part_count)
            ++counts[p];
        else
            ++rest;
    }
    size_t starts[8];
    size_t end = kPad + size_t(rest);
    for (uint32_t p = 0; p < part_count; ++p) {
        if (counts[p] > capacity[p]) return false;
        starts[p] = (end + 7) / 8 * 8;
        end = starts[p] + kPad + capacity[p];
    }
    if (end > heap_.capacity()) return false;
    // Group the entries: the rest first, then part 0's, part 1's ... (std::partition: in place and
    // deterministic; the order inside a group does not matter, the heaps are rebuilt).
    Entry* first = &at(0);
    Entry* cut = std::partition(first, first + n, [&](const Entry& e) { return part_of(e.id) >= part_count; });
    for (uint32_t p = 0; p + 1 < part_count; ++p)
        cut = std::partition(cut, first + n, [&](const Entry& e) { return part_of(e.id) == p; });
    heap_.resize(end, Entry{0.0f, 0});
    // Move the groups to their regions, the last first (regions only lie further right).
    size_t group_end = kPad + size_t(n);
    for (uint32_t p = part_count; p-- > 0;) {
        const size_t group_begin = group_end - counts[p];
        Entry* dst = &heap_[starts[p] + kPad];
        std::memmove(dst, &heap_[group_begin], counts[p] * sizeof(Entry));
        group_end = group_begin;
        PartHeap& part = parts[p];
        part.at_ = dst;
        part.slot_ = slot_.data();
        part.size_ = counts[p];
        part.capacity_ = capacity[p];
    }
    for_parts(part_count, [&](uint32_t p) {
        PartHeap& part = parts[p];
        for (uint32_t i = 0; i < part.size_; ++i) slot_[part.at_[i].id].pos = i;
        if (part.size_ >= 2)
            for (uint32_t i = (part.size_ - 2) / kArity + 1; i-- > 0;)
                collapse_heap::siftDown(part.at_, slot_.data(), part.size_, i);
    });
    rest_size_ = rest;
    return true;
}

inline void CollapseQueue::merge(const PartHeap* parts, uint32_t part_count) {
    size_t end = kPad + size_t(rest_size_);
    for (uint32_t p = 0; p < part_count; ++p) {
        std::memmove(&heap_[end], parts[p].at_, parts[p].size_ * sizeof(Entry));
        end += parts[p].size_;
    }
    heap_.resize(end);
    for (uint32_t i = 0; i < uint32_t(size()); ++i) setPos(at(i).id, i);
    heapify();
    rest_size_ = 0;
}

} // namespace lodbake::detail
