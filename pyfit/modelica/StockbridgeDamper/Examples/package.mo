within StockbridgeDamper;
package Examples "Example systems exported as FMUs"
end Examples;
