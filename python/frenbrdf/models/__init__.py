"""The networks: set encoder, hypernetwork decoder and the decoded NBRDF; refinement and edits of materials."""

from .autoencoder import AutoEncoder, Model, ModelConfig, interpolate
from .editing import EditedMaterial, edit
from .encoder import EncoderConfig, SetEncoder
from .hypernetwork import DecoderConfig, HyperNetwork
from .nbrdf import NBRDF, NBRDFConfig, nbrdf_coordinates, nbrdf_forward

__all__ = ["AutoEncoder", "DecoderConfig", "EditedMaterial", "EncoderConfig", "HyperNetwork", "Model", "ModelConfig",
           "NBRDF", "NBRDFConfig", "SetEncoder", "edit", "interpolate", "nbrdf_coordinates", "nbrdf_forward"]
