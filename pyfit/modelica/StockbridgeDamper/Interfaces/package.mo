within StockbridgeDamper;
package Interfaces "Connectors and partial models"
end Interfaces;
