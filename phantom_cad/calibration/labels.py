"""A text column of a measurement table (the sweep labels) as integer codes into its labels."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np


@dataclass(frozen=True, eq=False)
class Labels(Sequence):
    """A text column as codes into its distinct labels: ``labels[codes[k]]`` is row k. Reads like
    a tuple of str; costs one small int per row instead of one str object."""

    labels: tuple[str, ...]
    codes: np.ndarray

    def __len__(self) -> int:
        return len(self.codes)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return tuple(self.labels[c] for c in self.codes[k].tolist())
        return self.labels[self.codes[k]]

    def __iter__(self):
        labels = self.labels
        return (labels[c] for c in self.codes.tolist())

    def in_order_of_appearance(self) -> "Labels":
        """The same column, its labels numbered in order of first appearance."""
        if not len(self.codes):
            return Labels((), self.codes)
        used, first = np.unique(self.codes, return_index=True)
        order = used[np.argsort(first, kind="stable")]
        renumber = np.empty(len(self.labels), dtype=np.int64)
        renumber[order] = np.arange(order.size)
        return Labels(tuple(self.labels[c] for c in order.tolist()), renumber[self.codes])
