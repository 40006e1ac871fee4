"""Pictures: shaded relief of height maps, reward and feature maps, kept templates."""
