"""The spherical harmonic analysis as a differentiable torch operation.

Forward runs :meth:`frenbrdf.numerics.sht.SHT.analysis`; backward runs its exact adjoint
:meth:`~frenbrdf.numerics.sht.SHT.analysis_adjoint`. Both run in the native core on the CPU:
tensors on another device are copied to the CPU and back.

Examples
--------
>>> import torch
>>> from frenbrdf.numerics.sht_torch import SHTAnalysis
>>> analysis = SHTAnalysis(nlat=16, nlon=32, lmax=15)
>>> maps = torch.randn(3, 16, 32, dtype=torch.float64, requires_grad=True)
>>> analysis(maps).square().sum().backward()
>>> maps.grad.shape
torch.Size([3, 16, 32])
"""

from __future__ import annotations

import torch

from .sht import SHT


def _run(function, tensor: torch.Tensor) -> torch.Tensor:
    result = function(tensor.detach().cpu().numpy())
    return torch.from_numpy(result).to(device=tensor.device, dtype=tensor.dtype)


class SHTAnalysisFunction(torch.autograd.Function):
    """``apply(maps, sht)``: maps ``(..., nlat, nlon)`` → coefficients ``(..., (lmax+1)²)``."""

    @staticmethod
    def forward(ctx, maps: torch.Tensor, sht: SHT) -> torch.Tensor:
        ctx.sht = sht
        return _run(sht.analysis, maps)

    @staticmethod
    def backward(ctx, grad_coefficients: torch.Tensor):
        return _run(ctx.sht.analysis_adjoint, grad_coefficients.contiguous()), None


class SHTAnalysis(torch.nn.Module):
    """Differentiable analysis on a fixed grid; one plan per input dtype, built on first use.

    Parameters are those of :class:`frenbrdf.numerics.sht.SHT`, less the dtype, which follows the
    input (float64 or float32).
    """

    def __init__(self, nlat: int, nlon: int, lmax: int, grid: str = "gauss"):
        super().__init__()
        self.nlat, self.nlon, self.lmax, self.grid = nlat, nlon, lmax, grid
        self._plans: dict[torch.dtype, SHT] = {torch.float64: SHT(nlat, nlon, lmax, grid, "float64")}

    def plan(self, dtype: torch.dtype) -> SHT:
        if dtype not in (torch.float64, torch.float32):
            raise ValueError(f"SHTAnalysis takes float64 or float32 tensors, got {dtype}")
        if dtype not in self._plans:
            self._plans[dtype] = SHT(self.nlat, self.nlon, self.lmax, self.grid, str(dtype).removeprefix("torch."))
        return self._plans[dtype]

    def forward(self, maps: torch.Tensor) -> torch.Tensor:
        return SHTAnalysisFunction.apply(maps, self.plan(maps.dtype))

    def extra_repr(self) -> str:
        return f"nlat={self.nlat}, nlon={self.nlon}, lmax={self.lmax}, grid={self.grid!r}"
