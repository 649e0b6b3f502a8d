"""Training: configs and presets, the prepared data, one optimisation step, the loop, run folders.

- :mod:`.config`: :class:`TrainConfig`, :func:`config_for`, :func:`load_config`;
- :mod:`.prepared`: the materials read, mapped and their true SH coefficients;
- :mod:`frenbrdf.training.augment`, :mod:`frenbrdf.training.patterns`: each step's batch (augmented materials, the
  sampling patterns the encoder reads them through);
- :mod:`.step`: the loss composed, one optimisation step;
- :mod:`.loop`: :func:`train`;
- :mod:`.decoder_fit`: :func:`fit_decoder`, a trained run's decoder fitted further with free latents;
- :mod:`.run`: :class:`Run`, a run folder opened (what :func:`train` returns).
"""

from ..exceptions import TrainingDiverged
from .config import TrainConfig, config_for, load_config
from .decoder_fit import DecoderFitConfig, fit_decoder
from .loop import evaluate_split, train
from .prepared import Distributed, PreparedData, prepare, select_device
from .run import Run
from .step import LossTerms, loss_terms, optimisation_step

__all__ = ["DecoderFitConfig", "Distributed", "LossTerms", "PreparedData", "Run", "TrainConfig", "TrainingDiverged",
           "config_for", "evaluate_split", "fit_decoder", "load_config", "loss_terms", "optimisation_step", "prepare",
           "select_device", "train"]
